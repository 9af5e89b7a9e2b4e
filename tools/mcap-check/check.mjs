#!/usr/bin/env node
// Read MCAP files the way Foxglove does (@mcap/core's indexed reader) and check every byte:
// summary CRC (on open), data-section CRC (streamed over the file), chunk CRCs (while reading messages),
// and the message counts against the summary statistics.
//
// usage: node check.mjs FILE.mcap [FILE.mcap ...]
// stdout: {"FILE.mcap": {"/topic": count, ...}, ...} for the files that passed
// stderr: one line per failed file; the exit status is 1 if any file failed, 2 on bad usage.

import { open } from "node:fs/promises";

import { crc32Final, crc32Init, crc32Update } from "@foxglove/crc";
import lz4 from "@foxglove/wasm-lz4";
import zstd from "@foxglove/wasm-zstd";
import { McapIndexedReader } from "@mcap/core";

const BLOCK = 1 << 20;

await Promise.all([zstd.isLoaded, lz4.isLoaded]);
const decompressHandlers = {
  zstd: (data, size) => new Uint8Array(zstd.decompress(data, Number(size))),
  lz4: (data, size) => new Uint8Array(lz4(data, Number(size))),
};

/** An IReadable over an open file handle (offsets and sizes are bigints in @mcap/core). */
function fileReadable(handle, size) {
  return {
    size: async () => BigInt(size),
    read: async (offset, length) => {
      const buffer = new Uint8Array(Number(length));
      const { bytesRead } = await handle.read(buffer, 0, buffer.length, Number(offset));
      if (bytesRead !== buffer.length) {
        throw new Error(`short read at ${offset}: ${bytesRead} of ${length} bytes`);
      }
      return buffer;
    },
  };
}

async function checkDataSectionCrc(readable, reader) {
  if (reader.dataSectionCrc === undefined) {
    return; // the writer recorded none
  }
  let crc = crc32Init();
  for (let offset = 0n; offset < reader.dataEndOffset; offset += BigInt(BLOCK)) {
    const left = reader.dataEndOffset - offset;
    crc = crc32Update(crc, await readable.read(offset, left < BLOCK ? left : BigInt(BLOCK)));
  }
  crc = crc32Final(crc);
  if (crc !== reader.dataSectionCrc) {
    throw new Error(`incorrect data section CRC ${crc} (expected ${reader.dataSectionCrc})`);
  }
}

async function checkFile(path) {
  const handle = await open(path, "r");
  try {
    const { size } = await handle.stat();
    const readable = fileReadable(handle, size);
    const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
    await checkDataSectionCrc(readable, reader);
    const counts = {};
    const perChannel = new Map();
    for await (const message of reader.readMessages({ validateCrcs: true })) {
      const { topic } = reader.channelsById.get(message.channelId);
      counts[topic] = (counts[topic] ?? 0) + 1;
      perChannel.set(message.channelId, (perChannel.get(message.channelId) ?? 0n) + 1n);
    }
    for await (const _ of reader.readMetadata()) {
      // parsing each Metadata record is the check
    }
    if (reader.statistics) {
      for (const [id, expected] of reader.statistics.channelMessageCounts) {
        const got = perChannel.get(id) ?? 0n;
        if (got !== expected) {
          throw new Error(`channel ${id}: read ${got} messages, statistics say ${expected}`);
        }
      }
    }
    return counts;
  } finally {
    await handle.close();
  }
}

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error("usage: node check.mjs FILE.mcap [FILE.mcap ...]");
  process.exit(2);
}
const report = {};
let failed = 0;
for (const file of files) {
  try {
    report[file] = await checkFile(file);
  } catch (error) {
    failed += 1;
    const text = String(error?.message ?? error).replace(/\s+/g, " ");
    console.error(`${file}: ${text}`);
  }
}
console.log(JSON.stringify(report, null, 2));
process.exitCode = failed ? 1 : 0;
