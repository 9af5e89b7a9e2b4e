"""One trial: train-ppo then evaluate under the trial's Params, and the record of what it measured.

Runs wherever Ray puts it (a worker process, maybe on another node) or in-process; it only needs the project
folder at the same path (relative paths in the params, such as ppo.encoder_dir, resolve against it).
"""

from __future__ import annotations

import json
import os
import socket
import time
from pathlib import Path
from typing import Any

from hexpipe.config import Params

# evaluate's per-episode columns the sweep keeps, read by name (results.csv may gain columns)
EPISODE_COLUMNS = ("terrain", "controller", "episode", "seed", "success", "termination", "distance", "time",
                   "cost_of_transport", "energy_j", "a_mean", "b_mean", "omega_mean",
                   "b_before_block", "b_open",  # mean lift b (rad) in the 0.3 m before a block's face / on open ground
                   "stall_legs")  # stuck or fallen: the legs with a foot at a block face


def read_episodes(results_csv: Path) -> list[dict[str, Any]]:
    """evaluate's results.csv without the best_fixed search rows, restricted to EPISODE_COLUMNS that exist."""
    import pandas as pd

    rows = pd.read_csv(results_csv)
    rows = rows[rows["controller"] != "grid"]
    return json.loads(rows[[c for c in EPISODE_COLUMNS if c in rows.columns]].to_json(orient="records"))


def run_trial(params: Params, root: str | None = None) -> dict[str, Any]:
    """Train (resuming from the trial's own checkpoints if an earlier run was cut off), evaluate, and return the
    record: the trial's seconds, where it ran, PPO's final training figures and every evaluated episode."""
    from hexpipe.evaluation.run import evaluate
    from hexpipe.provenance import code_fingerprint
    from hexpipe.rl.train import train_ppo

    if root is not None:
        os.chdir(root)
    started = time.perf_counter()
    metrics = train_ppo(params, resume=True, show_progress=False)
    trained = time.perf_counter()
    evaluate(params, show_progress=False)
    finished = time.perf_counter()
    return {
        "seconds": {"train": trained - started, "evaluate": finished - trained, "total": finished - started},
        "host": socket.gethostname(), "node": _node_id(), "code": code_fingerprint(),
        "ppo": {k: v for k, v in metrics.items() if not k.startswith("time/") and v is not None},
        "episodes": read_episodes(Path(params.eval.report_dir) / "results.csv"),
    }


def _node_id() -> str | None:
    try:
        import ray

        return ray.get_runtime_context().get_node_id() if ray.is_initialized() else None
    except Exception:  # not in a Ray worker: no node
        return None
