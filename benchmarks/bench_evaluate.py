"""What the evaluate stage costs with the default suite and grid: a tiny policy (as the tests train one, seeing
the height map through an untrained VAE encoder) through `evaluate` with fewer episodes per terrain, then the
default's cost extrapolated from the measured per-episode times.

Usage: python benchmarks/bench_evaluate.py [--episodes 4] [--out reports/bench/evaluate.json]
       python benchmarks/bench_evaluate.py --results reports/eval/results.csv   # extrapolate an earlier run's times

The best-fixed-gait grid runs its full default size (it does not scale with eval.episodes); the suite's episodes
scale linearly. A tiny policy barely moves the CPG, so it stalls at blocks like the open-loop gait; a trained policy
that wanders until the time limit costs more, so the report also gives that worst case (every learned episode
running 40 s). Times are wall-clock on whatever else the machine is doing: the load average is recorded beside them.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

import pandas as pd

from hexpipe.config import Params, load_params
from hexpipe.evaluation.run import GRID_SEEDS, evaluate
from hexpipe.models.vae import ConvVAE, encoder_config, export_encoder
from hexpipe.rl.train import train_ppo

ROOT = Path(__file__).resolve().parents[1]
TINY_PPO = ["ppo.total_timesteps=256", "ppo.n_envs=1", "ppo.train_terrains=[single_block]", "ppo.n_steps=128",
            "ppo.batch_size=64", "ppo.n_epochs=1"]


def _kind(row: pd.Series, params: Params) -> str:
    """Episodes that cost differently: the grid, fixed gaits, and the policy's filmed, logged and plain episodes."""
    if row["controller"] != "policy":
        return "grid" if row["controller"] == "grid" else "fixed"
    if row["episode"] == 0 and params.eval.record_video:
        return "policy_filmed"
    return "policy_logged" if row["episode"] < params.eval.log_episodes else "policy"


def extrapolate(rows: pd.DataFrame, default: Params) -> dict:
    """Per kind of episode: measured mean wall time, steps and median ms per step; the default run's expected wall
    time (every kind's episode count in the default run x its mean time / workers) and its worst case (every
    learned episode running to the time limit)."""
    rows = rows.assign(kind=rows.apply(_kind, axis=1, params=default),
                       ms_per_step=1000 * rows["wall_s"] / rows["steps"])
    per = rows.groupby("kind").agg(episodes=("wall_s", "size"), episode_s=("wall_s", "mean"), steps=("steps", "mean"),
                                   ms_per_step=("ms_per_step", "median"))
    terrains, episodes, logged = len(default.eval.terrains), default.eval.episodes, default.eval.log_episodes
    counts = pd.Series({"grid": per.loc["grid", "episodes"], "fixed": 2 * terrains * episodes,
                        "policy_filmed": terrains, "policy_logged": terrains * (logged - 1),
                        "policy": terrains * (episodes - logged)}).reindex(per.index)
    workers = default.eval.workers
    expected = float((counts * per["episode_s"]).sum()) / workers
    limit_steps = default.task.time_limit * default.sim.control_hz
    learned = per.index.str.startswith("policy")
    extra = (counts * (limit_steps - per["steps"]).clip(lower=0) * per["ms_per_step"] / 1000)[learned].sum()
    return {"per_kind": {k: {c: round(float(v), 3) for c, v in r.items()} for k, r in per.iterrows()},
            "default_episodes": episodes, "expected_default_wall_s": round(expected),
            "worst_case_default_wall_s": round(expected + float(extra) / workers)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--episodes", type=int, default=4, help="per terrain; more than eval.log_episodes (2)")
    parser.add_argument("--out", type=Path, default=ROOT / "reports/bench/evaluate.json")
    parser.add_argument("--results", type=Path, help="only extrapolate from this results.csv (no new run)")
    args = parser.parse_args()
    default = load_params(ROOT / "params.yaml")
    if args.results is not None:
        print(json.dumps({"results": str(args.results), **extrapolate(pd.read_csv(args.results), default)}, indent=2))
        return
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        model = ConvVAE(in_channels=1, image_size=64, latent_dim=8)
        export_encoder(model, root / "vae", encoder_config(model, "heightmap", (32, 32)))
        params = load_params(ROOT / "params.yaml", [
            *TINY_PPO, f"ppo.encoder_dir={root / 'vae'}", f"ppo.out_dir={root / 'ppo'}",
            f"ppo.report_dir={root / 'ppo-report'}", f"eval.policy_dir={root / 'ppo'}",
            f"eval.out_dir={root / 'eval'}", f"eval.report_dir={root / 'report'}", f"eval.episodes={args.episodes}",
        ])
        train_ppo(params, show_progress=False)  # one env: one training terrain
        params = params.model_copy(update={"ppo": params.ppo.model_copy(
            update={"train_terrains": default.ppo.train_terrains})})  # the default grid: every training terrain
        load_before = os.getloadavg()[0]
        start = time.perf_counter()
        evaluate(params, show_progress=False)
        wall = time.perf_counter() - start
        rows = pd.read_csv(root / "report" / "results.csv")
    report = {"episodes_per_terrain": args.episodes, "terrains": len(default.eval.terrains),
              "workers": params.eval.workers, "grid_seeds": GRID_SEEDS, "measured_wall_s": round(wall, 1),
              **extrapolate(rows, default),
              "load_average_before": round(load_before, 2), "load_average_after": round(os.getloadavg()[0], 2)}
    print(json.dumps(report, indent=2))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=2) + "\n")


if __name__ == "__main__":
    main()
