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


def move_speed(metrics_path: Path, speed_path: Path, speed_keys: Iterable[str]) -> dict[str, Any]:
    """Rewrite metrics_path without `speed_keys` and write them to speed_path (both atomically); returns speed."""
    results, speed = split(json.loads(Path(metrics_path).read_text()), speed_keys)
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
