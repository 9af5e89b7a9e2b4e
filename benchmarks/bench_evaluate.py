"""What the evaluate stage costs with the default suite and grid: a tiny policy (as the tests train one, seeing
the height map through an untrained VAE encoder) through `evaluate` with fewer episodes per terrain, then the
default's cost extrapolated from the measured per-episode times.

Usage: python benchmarks/bench_evaluate.py [--episodes 4] [--out reports/bench/evaluate.json]

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

from hexpipe.config import load_params
from hexpipe.evaluation.run import GRID_SEEDS, WORKERS, evaluate
from hexpipe.models.vae import ConvVAE, encoder_config, export_encoder
from hexpipe.rl.train import train_ppo

ROOT = Path(__file__).resolve().parents[1]
TINY_PPO = ["ppo.total_timesteps=256", "ppo.n_envs=1", "ppo.train_terrains=[single_block]", "ppo.n_steps=128",
            "ppo.batch_size=64", "ppo.n_epochs=1"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--episodes", type=int, default=4)
    parser.add_argument("--out", type=Path, default=ROOT / "reports/bench/evaluate.json")
    args = parser.parse_args()
    default = load_params(ROOT / "params.yaml")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        model = ConvVAE(in_channels=1, image_size=64, latent_dim=8)
        export_encoder(model, root / "vae", encoder_config(model, "heightmap", (32, 32)))
        params = load_params(ROOT / "params.yaml", [
            *TINY_PPO, f"ppo.encoder_dir={root / 'vae'}", f"ppo.out_dir={root / 'ppo'}",
            f"ppo.report_dir={root / 'ppo-report'}", f"eval.policy_dir={root / 'ppo'}",
            f"eval.out_dir={root / 'eval'}", f"eval.report_dir={root / 'report'}", f"eval.episodes={args.episodes}",
        ])
        train_ppo(params, show_progress=False)
        load_before = os.getloadavg()[0]
        start = time.perf_counter()
        evaluate(params, show_progress=False)
        wall = time.perf_counter() - start
        rows = pd.read_csv(root / "report" / "results.csv")
    per = rows.groupby(rows["controller"] == "grid").agg(episodes=("wall_s", "size"), wall_s=("wall_s", "sum"),
                                                          steps=("steps", "sum"))
    grid, suite = per.loc[True], per.loc[False]
    scale = default.eval.episodes / args.episodes
    learned = rows[rows["controller"] == "policy"]
    s_per_policy_step = float(learned["wall_s"].sum() / learned["steps"].sum())
    limit_steps = default.task.time_limit * default.sim.control_hz
    learned_default = len(default.eval.terrains) * default.eval.episodes  # policy episodes in the default run
    expected = (grid["wall_s"] + suite["wall_s"] * scale) / WORKERS
    worst = expected + learned_default * (limit_steps * s_per_policy_step - learned["wall_s"].mean()) / WORKERS
    report = {
        "episodes_per_terrain": args.episodes, "terrains": len(default.eval.terrains), "workers": WORKERS,
        "grid_episodes": int(grid["episodes"]), "grid_seeds": GRID_SEEDS, "suite_episodes": int(suite["episodes"]),
        "measured_wall_s": round(wall, 1), "grid_episode_s": round(float(grid["wall_s"] / grid["episodes"]), 3),
        "suite_episode_s": round(float(suite["wall_s"] / suite["episodes"]), 3),
        "policy_step_ms": round(1000 * s_per_policy_step, 3),
        "default_episodes": default.eval.episodes,
        "expected_default_wall_s": round(float(expected), 0),
        "worst_case_default_wall_s": round(float(worst), 0),
        "load_average_before": round(load_before, 2), "load_average_after": round(os.getloadavg()[0], 2),
    }
    print(json.dumps(report, indent=2))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=2) + "\n")


if __name__ == "__main__":
    main()
