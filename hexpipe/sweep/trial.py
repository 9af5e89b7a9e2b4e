"""One trial: (train-vae, with sweep.train_encoder,) train-ppo (every candidate, validated) then evaluate under the
trial's Params, and the record of what it measured.

Runs wherever Ray puts it (a worker process, maybe on another node) or in-process; it only needs the project
folder at the same path (relative paths in the params, such as ppo.encoder_dir, resolve against it).
"""

from __future__ import annotations

import fcntl
import json
import os
import socket
import time
from pathlib import Path
from typing import Any

from hexpipe.config import Params

# the encoder's report figures a trial record keeps (train-vae's metrics.json keys)
ENCODER_METRICS = ("probe/rise_distance_r2", "probe/rise_height_r2", "probe_accuracy", "val/recon", "val/kl")

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
    from hexpipe.rl.selection import SELECTION, train_policy

    if root is not None:
        os.chdir(root)
    started = time.perf_counter()
    encoder = train_encoder(params) if params.sweep.train_encoder else None
    encoded = time.perf_counter()
    metrics = train_policy(params, resume=True, show_progress=False)
    trained = time.perf_counter()
    evaluate(params, show_progress=False)
    finished = time.perf_counter()
    return {
        "seconds": {"vae": encoded - started, "train": trained - encoded, "evaluate": finished - trained,
                    "total": finished - started},
        "host": socket.gethostname(), "node": _node_id(), "code": code_fingerprint(),
        **({"vae": encoder} if encoder is not None else {}),
        "ppo": {k: v for k, v in metrics.items() if not k.startswith("time/") and v is not None},
        "selection": json.loads((Path(params.ppo.report_dir) / SELECTION).read_text()),  # every candidate's scores
        "episodes": read_episodes(Path(params.eval.report_dir) / "results.csv"),
    }


def train_encoder(params: Params) -> dict[str, Any]:
    """train-vae into the trial's vae.out_dir, on as many threads as the trial reserves. One trial at a time per
    encoder (a lock file beside it): a second trial that needs the same encoder finds the finished checkpoint and
    only re-exports it. Returns the encoder's name and its report figures."""
    from rich.console import Console

    from hexpipe.models.train_vae import train_vae
    from hexpipe.sweep.grid import trial_cpus

    out = Path(params.vae.out_dir)
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out.parent / f"{out.name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes, also if this process dies
        metrics = train_vae(params.vae, threads=trial_cpus(params), console=Console(quiet=True))
    return {"encoder": out.name, **{k: metrics[k] for k in ENCODER_METRICS if k in metrics}}


def _node_id() -> str | None:
    try:
        import ray

        return ray.get_runtime_context().get_node_id() if ray.is_initialized() else None
    except Exception:  # not in a Ray worker: no node
        return None
