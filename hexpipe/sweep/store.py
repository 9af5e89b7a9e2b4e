"""Trial records on disk: what makes a trial complete, so a rerun of the sweep skips it.

A trial is complete when report_dir/NAME/TRIAL/result.json exists, says "ok" and carries the trial's key (the hash
of its params). It is written atomically by the driver when the trial's task returns, so a kill -9 at any moment
leaves either the whole record or none. A failed trial gets failure.json instead (its error and traceback); a
rerun tries it again and removes that file on success.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from hexpipe.atomic import write_json
from hexpipe.config import Params
from hexpipe.sweep.grid import Trial, trial_dirs

RESULT = "result.json"
FAILURE = "failure.json"


def result_path(params: Params, trial: Trial) -> Path:
    return trial_dirs(params, trial.name)[1] / RESULT


def failure_path(params: Params, trial: Trial) -> Path:
    return trial_dirs(params, trial.name)[1] / FAILURE


def load_result(params: Params, trial: Trial) -> dict[str, Any] | None:
    """The trial's stored record if it is complete under the trial's current params, else None."""
    path = result_path(params, trial)
    try:
        record = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return record if record.get("status") == "ok" and record.get("key") == trial.key else None


def save_result(params: Params, trial: Trial, record: dict[str, Any]) -> None:
    write_json(result_path(params, trial), {**record, "status": "ok", "key": trial.key})
    failure_path(params, trial).unlink(missing_ok=True)


def save_failure(params: Params, trial: Trial, error: str, details: str) -> dict[str, Any]:
    record = {"trial": trial.name, "condition": trial.condition, "seed": trial.seed, "status": "failed",
              "key": trial.key, "error": error, "traceback": details}
    write_json(failure_path(params, trial), record)
    return record


def load_failure(params: Params, trial: Trial) -> dict[str, Any] | None:
    try:
        record = json.loads(failure_path(params, trial).read_text())
    except (OSError, ValueError):
        return None
    return record if record.get("key") == trial.key else None
