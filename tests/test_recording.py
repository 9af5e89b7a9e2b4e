"""EpisodeWriter -> MCAP -> iter_frames round trip, corrupt files, and Foxglove's own reader (@mcap/core)."""

from __future__ import annotations

import json
import shutil
import struct
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mcap.reader import NonSeekingReader, make_reader

from hexpipe.recording import (
    EpisodeWriter,
    JsonDecoderFactory,
    RecordingError,
    count_messages,
    iter_frames,
    read_metadata,
)
from hexpipe.recording.reader import _fields  # protobuf field splitter, to look inside Foxglove messages
from hexpipe.recording.writer import (
    HEIGHT_FIELD,
    TOPIC_CPG,
    TOPIC_ROBOT,
    TOPIC_STEP,
    TOPIC_TERRAIN,
    TOPIC_TF,
)
from hexpipe.sensors import SENSORS, Message

TOPIC_IMAGE, TOPIC_HEIGHTMAP = SENSORS["rgb"].topic, SENSORS["heightmap"].topic
MCAP_CHECK = Path(__file__).resolve().parents[1] / "tools" / "mcap-check"
STEPS = 12
DT_NS = 50_000_000  # 20 Hz control
HEIGHTMAP_SHAPE = (24, 16)  # rows (along x) != columns (along y): a transposition cannot go unnoticed
CELL = (0.06, 0.1)  # m along x, along y
LEGS = 6
JOINT_NAMES = [f"leg{leg}_{j}" for leg in range(LEGS) for j in ("yaw", "shoulder", "knee")]
FRAMES = ["base_link", *(f"leg{leg}_{link}" for leg in range(LEGS) for link in ("coxa", "femur", "tibia"))]


@dataclass(frozen=True)
class Box:
    center: tuple[float, float, float]
    size: tuple[float, float, float]
    yaw: float
    rgba: tuple[float, float, float, float]


@dataclass(frozen=True)
class Heightfield:
    origin: tuple[float, float]
    cell: float
    heights: np.ndarray


@dataclass
class Episode:
    path: Path
    metadata: dict[str, dict[str, str]]
    rgb: list[np.ndarray]
    heightmap: list[np.ndarray]
    step: list[dict[str, Any]]
    cpg: list[dict[str, Any]]


def write_episode(path: Path, seed: int = 0, steps: int = STEPS) -> Episode:
    rng = np.random.default_rng(seed)
    metadata = {
        "episode": {"terrain": "random_blocks", "seed": str(seed), "policy": "random"},
        "terrain": {"json": json.dumps({"boxes": 2})},
        "params": {"sim.control_hz": "20"},
    }
    boxes = [
        Box((1.0, 0.0, 0.05), (0.2, 1.0, 0.1), 0.3, (0.8, 0.2, 0.2, 1.0)),
        Box((2.0, 0.5, 0.1), (0.3, 0.3, 0.2), -1.0, (0.2, 0.8, 0.2, 1.0)),
    ]
    field = Heightfield((3.0, -0.5), 0.1, rng.uniform(0, 0.05, (6, 5)))
    episode = Episode(path, metadata, [], [], [], [])
    with EpisodeWriter(path, metadata) as writer:
        writer.log_scene(0, boxes, [field])
        for k in range(steps):
            rgb = rng.integers(0, 256, (64, 64, 3), dtype=np.uint8)
            heightmap = rng.normal(0, 0.1, HEIGHTMAP_SHAPE).astype(np.float32)
            transforms = [
                ("world" if name == "base_link" else "base_link", name, rng.normal(size=3), _unit_quat(rng))
                for name in FRAMES
            ]
            cpg = {
                "a": float(rng.uniform(0.05, 0.4)),
                "b": float(rng.uniform(0.05, 0.5)),
                "omega": 4.7,
                "a_rate": 0.0,
                "x": rng.normal(size=LEGS).tolist(),
            }
            step = {
                "reward": float(rng.normal()),
                "distance": 0.01 * k,
                "obstacle_distance": 0.8,
                "terrain": "random_blocks",
                "termination": "" if k < steps - 1 else "time_limit",
            }
            writer.log_step(
                (k + 1) * DT_NS,
                transforms=transforms,
                sensors=[Message(TOPIC_IMAGE, "image", rgb, "camera"), Message(
                    TOPIC_HEIGHTMAP, "grid",
                    (heightmap, (np.array([-0.2, -0.8, 0.0]), np.array([0.0, 0.0, 0.0, 1.0]), CELL)), "heading",
                )],
                joints={
                    "name": JOINT_NAMES,
                    "position": rng.normal(size=18),
                    "velocity": rng.normal(size=18).tolist(),
                    "effort": [0.0] * 18,
                },
                cpg=cpg,
                step=step,
            )
            episode.rgb.append(rgb)
            episode.heightmap.append(heightmap)
            episode.step.append(step)
            episode.cpg.append(cpg)
    return episode


def _unit_quat(rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


@pytest.fixture(scope="module")
def episode(tmp_path_factory: pytest.TempPathFactory) -> Episode:
    return write_episode(tmp_path_factory.mktemp("rollouts") / "ep_0000.mcap")


def test_round_trip_frames_are_exact(episode: Episode) -> None:
    frames = list(iter_frames(episode.path))
    assert [f.step for f in frames] == list(range(STEPS))
    for frame, rgb, heightmap, step in zip(frames, episode.rgb, episode.heightmap, episode.step, strict=True):
        assert frame.episode == "ep_0000"
        frame_rgb, frame_heightmap = frame.sensors.get("rgb"), frame.sensors.get("heightmap")
        assert frame_rgb is not None and frame_rgb.dtype == np.uint8 and np.array_equal(frame_rgb, rgb)
        assert frame_heightmap is not None and frame_heightmap.dtype == np.float32
        assert np.array_equal(frame_heightmap, heightmap)
        assert frame.meta == step
    assert frames[0].sensors["rgb"].flags.writeable  # safe for torch.from_numpy


def test_metadata_and_counts(episode: Episode) -> None:
    assert read_metadata(episode.path) == episode.metadata
    per_step = ["/tf", "/camera/image", "/heightmap", "/joint_states", "/cpg", "/step"]
    assert count_messages(episode.path) == {"/terrain": 1, **dict.fromkeys(per_step, STEPS)}


def test_crc_validating_mcap_reads(episode: Episode) -> None:
    with open(episode.path, "rb") as f:  # indexed reader: summary, chunk CRCs
        reader = make_reader(f, validate_crcs=True, decoder_factories=[JsonDecoderFactory()])
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None and summary.chunk_indexes
        cpg = [m.decoded_message for m in reader.iter_decoded_messages(topics=["/cpg"])]
    assert cpg == episode.cpg
    with open(episode.path, "rb") as f:  # linear pass: also the data-section CRC
        records = list(NonSeekingReader(f, validate_crcs=True).iter_messages(log_time_order=False))
    assert len(records) == 1 + 6 * STEPS
    schemas = {channel.topic: (schema.name, schema.encoding) for schema, channel, _ in records if schema}
    assert schemas["/tf"] == ("foxglove.FrameTransforms", "protobuf")
    assert schemas["/camera/image"] == ("foxglove.RawImage", "protobuf")
    assert schemas["/heightmap"] == ("foxglove.Grid", "protobuf")
    assert schemas["/terrain"] == ("foxglove.SceneUpdate", "protobuf")
    assert {schemas[t][1] for t in ("/joint_states", "/cpg", "/step")} == {"jsonschema"}


def test_json_schemas_declare_types(episode: Episode) -> None:
    with open(episode.path, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    by_topic = {
        c.topic: json.loads(summary.schemas[c.schema_id].data)
        for c in summary.channels.values()
        if c.message_encoding == "json"
    }
    cpg = by_topic["/cpg"]["properties"]
    assert {cpg[k]["type"] for k in ("a", "b", "omega")} == {"number"}
    assert cpg["x"] == {"type": "array", "items": {"type": "number"}}
    assert by_topic["/step"]["properties"]["distance"]["type"] == "number"
    assert by_topic["/step"]["properties"]["termination"]["type"] == "string"
    assert by_topic["/joint_states"]["properties"]["name"]["items"]["type"] == "string"


def test_grid_and_scene_are_what_foxglove_draws(episode: Episode) -> None:
    with open(episode.path, "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        grid = next(m.data for _, _, m in reader.iter_messages(topics=["/heightmap"]))
        scene = next(m.data for _, _, m in reader.iter_messages(topics=["/terrain"]))
    # foxglove.Grid fields: 2 frame_id, 4 column_count, 5 cell_size, 6 row_stride, 7 cell_stride, 8 fields, 9 data
    g = _fields(grid)
    rows, cols = HEIGHTMAP_SHAPE
    assert g[2] == [b"heading"] and g[4] == [rows] and g[6] == [4 * rows] and g[7] == [4]
    cell_bits = [struct.unpack("<Q", struct.pack("<d", c))[0] for c in CELL]
    assert _fields(g[5][0]) == {1: [cell_bits[0]], 2: [cell_bits[1]]}  # Vector2 x, y (m)
    (field,) = g[8]
    assert _fields(field) == {1: [b"height"], 3: [7]}  # name "height", offset 0 (default), type FLOAT32
    # Foxglove draws data row k, column j at (x, y) = (j, k) cells from the corner: heightmap[j, k] belongs there
    drawn = np.frombuffer(g[9][0], "<f4").reshape(cols, rows)
    assert np.array_equal(drawn.T, episode.heightmap[0])
    entities = [_fields(e) for e in _fields(scene)[2]]  # SceneUpdate.entities
    assert [e[3] for e in entities] == [[b"boxes"], [b"heightfield/0"]]
    assert all(e[2] == [b"world"] for e in entities)
    assert len(entities[0][8]) == 2  # SceneEntity.cubes
    (mesh,) = entities[1][12]  # SceneEntity.triangles
    mesh_fields = _fields(mesh)
    assert len(mesh_fields[2]) == 6 * 5  # a vertex per height sample
    indices = np.frombuffer(mesh_fields[5][0], "<u4").reshape((6 - 1) * (5 - 1), 2, 3)  # 2 triangles per cell
    assert indices[0].tolist() == [[0, 5, 1], [5, 6, 1]]  # split along node (1, 0) - node (0, 1), like PyBullet


def test_foxglove_reader_reads_it(episode: Episode, tmp_path: Path) -> None:
    node = _node_or_skip()
    result = subprocess.run(
        [node, str(MCAP_CHECK / "check.mjs"), str(episode.path)], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout) == {str(episode.path): count_messages(episode.path)}
    bad = [
        _truncated(episode.path, tmp_path),
        *(_flipped(episode.path, tmp_path, at) for at in (0.3, 0.6, 0.999)),
    ]
    result = subprocess.run(
        [node, str(MCAP_CHECK / "check.mjs"), *map(str, bad)], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 1
    assert json.loads(result.stdout) == {}
    assert [line.split(": ")[0] for line in result.stderr.splitlines()] == list(map(str, bad))


def test_truncated_file_names_the_file(episode: Episode, tmp_path: Path) -> None:
    bad = _truncated(episode.path, tmp_path)
    for read in (lambda p: list(iter_frames(p)), read_metadata, count_messages):
        with pytest.raises(RecordingError) as info:
            read(bad)
        assert str(info.value).startswith(f"{bad}: truncated or corrupt MCAP (")
        assert "\n" not in str(info.value)


@pytest.mark.parametrize("at", [0.0, *np.linspace(0.01, 0.99, 40).tolist(), 1.0])
def test_flipped_byte_anywhere_is_caught(episode: Episode, tmp_path: Path, at: float) -> None:
    bad = _flipped(episode.path, tmp_path, at)
    with pytest.raises(RecordingError, match=f"^{bad}: "):
        list(iter_frames(bad))


def test_exception_inside_with_leaves_no_file(tmp_path: Path) -> None:
    path = tmp_path / "ep_0001.mcap"
    with (
        pytest.raises(RuntimeError, match="boom"),
        EpisodeWriter(path, {"episode": {"terrain": "flat"}}) as writer,
    ):
        writer.log_step(DT_NS, transforms=[], joints={}, cpg={"a": 0.1}, step={"distance": 0.0})
        raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []
    path.write_bytes(b"previous episode")  # an existing file survives a failed rewrite
    with pytest.raises(RuntimeError), EpisodeWriter(path, {}):
        raise RuntimeError
    assert path.read_bytes() == b"previous episode"
    assert list(tmp_path.iterdir()) == [path]


def test_folder_order_modalities_and_nonfinite(tmp_path: Path) -> None:
    write_episode(tmp_path / "ep_0002.mcap", seed=2, steps=2)
    write_episode(tmp_path / "ep_0001.mcap", seed=1, steps=3)
    frames = list(iter_frames(tmp_path, modalities=("heightmap",)))
    assert [(f.episode, f.step) for f in frames] == [
        ("ep_0001", 0),
        ("ep_0001", 1),
        ("ep_0001", 2),
        ("ep_0002", 0),
        ("ep_0002", 1),
    ]
    assert all(set(f.sensors) == {"heightmap"} for f in frames)
    path = tmp_path / "nan" / "ep.mcap"
    with EpisodeWriter(path, {"episode": {"terrain": "flat"}}) as writer:
        writer.log_step(
            DT_NS,
            transforms=[],
            joints={},
            cpg={"a": 0.1},
            step={"obstacle_distance": float("inf"), "reward": np.float32(1.5)},
        )
    (frame,) = iter_frames(path)
    assert frame.meta == {"obstacle_distance": None, "reward": 1.5, "terrain": "flat"}
    with pytest.raises(ValueError, match="modalities"):
        next(iter_frames(path, modalities=("depth",)))
    with pytest.raises(RecordingError, match="no such file or folder"):
        next(iter_frames(tmp_path / "missing"))
    (tmp_path / "empty").mkdir()
    with pytest.raises(RecordingError, match=r"no \.mcap files"):
        next(iter_frames(tmp_path / "empty"))


def test_log_step_time_must_increase(tmp_path: Path) -> None:
    with EpisodeWriter(tmp_path / "ep.mcap", {}) as writer:
        writer.log_step(DT_NS, transforms=[], joints={}, cpg={}, step={})
        with pytest.raises(ValueError, match="must exceed"):
            writer.log_step(DT_NS, transforms=[], joints={}, cpg={}, step={})


SCENE_SCHEMAS = {"foxglove.SceneUpdate", "foxglove.FrameTransforms", "foxglove.Grid"}  # what the 3D panel draws


def test_foxglove_layout_shows_every_scene_topic_the_recorder_writes(tmp_path: Path) -> None:
    """The topics come from a real episode logged by EpisodeLog, not from a copy of the list."""
    from hexpipe.envs.hexapod import HexapodEnv
    from hexpipe.recording.episode import EpisodeLog

    env = HexapodEnv("single_block")
    try:
        env.reset(seed=0)
        with EpisodeLog(env, tmp_path / "ep.mcap", {}) as log:
            log.step(0.0, force=True)
            _, reward, *_ = env.step(np.zeros(3, dtype=np.float32))
            log.step(reward, force=True)
    finally:
        env.close()
    with (tmp_path / "ep.mcap").open("rb") as f:
        summary = make_reader(f).get_summary()
    schemas = {c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()}
    scene = {topic for topic, schema in schemas.items() if schema in SCENE_SCHEMAS}
    assert {TOPIC_TF, TOPIC_ROBOT, TOPIC_TERRAIN, TOPIC_HEIGHTMAP} <= scene  # the recorder writes them all

    layout = json.loads((MCAP_CHECK.parents[1] / "layouts" / "hexpipe_layout.json").read_text())
    panels = layout["configById"]

    def leaves(node: Any) -> list[str]:
        return [node] if isinstance(node, str) else leaves(node["first"]) + leaves(node["second"])

    assert sorted(leaves(layout["layout"])) == sorted(panels)
    (three_d,) = (c for k, c in panels.items() if k.startswith("3D!"))
    assert three_d["followTf"] == "base_link"
    assert three_d["followMode"] in ("follow-pose", "follow-position")  # Foxglove's modes that follow a frame
    switched_on = {t for t, c in three_d["topics"].items() if c.get("visible")}
    assert scene <= switched_on, f"not shown in the 3D panel: {sorted(scene - switched_on)}"
    assert set(three_d["topics"]) <= set(schemas)  # no stale topic names
    assert three_d["topics"][TOPIC_HEIGHTMAP]["colorField"] == HEIGHT_FIELD
    (image,) = (c for k, c in panels.items() if k.startswith("Image!"))
    assert image["imageMode"]["imageTopic"] == TOPIC_IMAGE and schemas[TOPIC_IMAGE] == "foxglove.RawImage"
    plotted = {p["value"] for k, c in panels.items() if k.startswith("Plot!") for p in c["paths"]}
    assert plotted == {f"{TOPIC_CPG}.a", f"{TOPIC_CPG}.b", f"{TOPIC_CPG}.omega", f"{TOPIC_STEP}.distance"}
    assert {p.split(".")[0] for p in plotted} <= set(schemas)


@pytest.mark.slow
def test_log_step_cost(tmp_path: Path) -> None:
    """64x64 RGB + 32x32 heightmap + 19 transforms must stay far below the ~3 ms env step."""
    rng = np.random.default_rng(0)
    rgb = rng.integers(0, 256, (64, 64, 3), dtype=np.uint8)
    heightmap = rng.normal(size=(32, 32)).astype(np.float32)
    transforms = [("world", name, rng.normal(size=3), _unit_quat(rng)) for name in FRAMES]
    pose = (np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0]), 0.05)
    joints = {
        "name": JOINT_NAMES,
        "position": rng.normal(size=18).tolist(),
        "velocity": [0.0] * 18,
        "effort": [0.0] * 18,
    }
    cpg = {
        "a": 0.2,
        "b": 0.3,
        "omega": 4.7,
        "a_rate": 0.0,
        "b_rate": 0.0,
        "omega_rate": 0.0,
        "x": [0.0] * 6,
        "y": [0.0] * 6,
    }
    step = {
        "reward": 1.0,
        "distance": 0.5,
        "obstacle_distance": 0.7,
        "terrain": "single_block",
        "termination": "",
    }
    durations = []
    start = time.perf_counter()
    with EpisodeWriter(tmp_path / "ep.mcap", {}) as writer:
        for k in range(400):
            t0 = time.perf_counter()
            writer.log_step(
                (k + 1) * DT_NS,
                transforms=transforms,
                sensors=[Message(TOPIC_IMAGE, "image", rgb, "camera"),
                         Message(TOPIC_HEIGHTMAP, "grid", (heightmap, pose), "heading")],
                joints=joints,
                cpg=cpg,
                step=step,
            )
            durations.append(time.perf_counter() - t0)
    amortised = (time.perf_counter() - start) / len(durations)  # includes chunk compression and close
    assert float(np.median(durations)) < 0.5e-3 and amortised < 1e-3, (np.median(durations), amortised)


def _node_or_skip() -> str:
    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not on PATH (needed for the @mcap/core check)")
    if not (MCAP_CHECK / "node_modules" / "@mcap" / "core").is_dir():
        pytest.skip("tools/mcap-check/node_modules missing: run `cd tools/mcap-check && npm ci`")
    return node


def _truncated(path: Path, folder: Path) -> Path:
    data = path.read_bytes()
    out = folder / f"{path.stem}_truncated.mcap"
    out.write_bytes(data[: len(data) // 2])
    return out


def _flipped(path: Path, folder: Path, at: float) -> Path:
    data = bytearray(path.read_bytes())
    index = min(int(at * len(data)), len(data) - 1)
    data[index] ^= 0xFF
    out = folder / f"{path.stem}_flipped_{index}.mcap"
    out.write_bytes(bytes(data))
    return out
