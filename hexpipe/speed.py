"""Speed and throughput figures live in their own JSON file beside each stage's metrics.

Timings differ on every run, results do not: DVC declares only the results as metrics, so `dvc metrics diff`
between two runs shows what changed in the results, not timing noise. The speed files are plain outputs
(reports/collect_speed.json, reports/vae/speed.json, reports/ppo/speed.json), read by `hexpipe summary`.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from hexpipe.atomic import write_json

SPEED_JSON = "speed.json"


def beside(report: Path) -> Path:
    """The speed file of a report that is not in a folder of its own: reports/collect.json -> collect_speed.json."""
    report = Path(report)
    return report.with_name(f"{report.stem}_speed.json")


def split(tree: dict[str, Any], speed_keys: Iterable[str]) -> tuple[dict[str, Any], dict[str, Any]]:
    """(results, speed): each key in `speed_keys` ('name' or a nested 'section/name') moves from results to speed,
    keeping its nesting; sections left empty are dropped. `tree` is not modified."""
    results = json.loads(json.dumps(tree))
    speed: dict[str, Any] = {}
    for key in speed_keys:
        *sections, name = key.split("/")
        node, out = results, speed
        for section in sections:
            if not isinstance(node.get(section), dict):
                break
            node, out = node[section], out.setdefault(section, {})
        else:
            if name in node:
                out[name] = node.pop(name)
    for section in [k for k, v in results.items() if isinstance(v, dict) and not v and k in speed]:
        del results[section]
    return results, {k: v for k, v in speed.items() if v != {}}


def machine() -> dict[str, Any]:
    """The CPU a stage computed on. torch's float kernels (oneDNN, MKL) differ by instruction set, so the same data
    and seed give the same weights only on a machine of the same kind (README, Reproducibility); the speed file
    keeps this beside the timings, where `dvc metrics diff` does not see it."""
    import platform

    import torch

    model = platform.processor() or platform.machine()
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.is_file():
        names = [line.split(":", 1)[1].strip() for line in cpuinfo.read_text().splitlines()
                 if line.startswith("model name")]
        model = names[0] if names else model
    return {"cpu": model, "arch": platform.machine(), "torch": torch.__version__,
            "torch_cpu_capability": torch.backends.cpu.get_cpu_capability(), "torch_threads": torch.get_num_threads()}


def move_speed(
    metrics_path: Path, speed_path: Path, speed_keys: Iterable[str], made_on: dict[str, Any] | None = None
) -> dict[str, Any]:
    """Rewrite metrics_path without `speed_keys` and write them to speed_path (both atomically), with `made_on`
    (see `machine`) under "machine" if given; returns the speed file's contents."""
    results, speed = split(json.loads(Path(metrics_path).read_text()), speed_keys)
    if made_on is not None:
        speed["machine"] = made_on
    write_json(speed_path, speed)
    write_json(metrics_path, results)
    return speed


def read_with_speed(metrics_path: Path, speed_path: Path) -> dict[str, Any] | None:
    """A stage's metrics merged with its speed file (one level deep), for pages that show both; None if no metrics."""
    if not Path(metrics_path).is_file():
        return None
    merged = json.loads(Path(metrics_path).read_text())
    if Path(speed_path).is_file():
        for key, value in json.loads(Path(speed_path).read_text()).items():
            if isinstance(value, dict) and isinstance(merged.get(key), dict):
                merged[key] = {**merged[key], **value}
            else:
                merged[key] = value
    return merged
