"""What the collapsed seeds have in common, from the committed sweep records: per trial, success over the suite and
on single_block, and the curriculum level (mean of the last 40k steps, and the highest reached); then, for one
trained policy, single_block success acting deterministically and stochastically.

    .venv/bin/python reports/experiments/seed_collapse.py --policy data/sweeps/forward/torch-seed3/ppo
"""

import argparse
import csv
import json
from pathlib import Path

import numpy as np

SWEEPS = ("privileged/default", "levers/default", "levers/pen300", "levers/gamma995", "forward/torch",
          "forward/numpy", "penalty/price02_pen1000", "penalty/rear_map")


def levels(trial: Path) -> tuple[float, float]:
    with (trial / "ppo/plots/metrics/curriculum/difficulty.tsv").open() as f:
        rows = [(int(r["step"]), float(r["difficulty"])) for r in csv.DictReader(f, delimiter="\t")]
    return float(np.mean([d for s, d in rows if s > 80_000])), max(d for _, d in rows)


def trials() -> None:
    for name in SWEEPS:
        sweep, condition = name.split("/")
        for result in sorted(Path("reports/sweeps", sweep).glob(f"{condition}-seed*/result.json")):
            episodes = [e for e in json.loads(result.read_text())["episodes"] if e["controller"] == "policy"]
            block = [e["success"] for e in episodes if e["terrain"] == "single_block"]
            late, top = levels(result.parent)
            print(f"{sweep}/{result.parent.name:24s} suite {np.mean([e['success'] for e in episodes]):.2f}  "
                  f"single_block {np.mean(block):.1f}  level (last 40k) {late:.2f}  highest {top:.2f}")


def acting(policy_dir: str, episodes: int) -> None:
    import torch

    from hexpipe.envs.hexapod import HexapodEnv
    from hexpipe.rl.policy import load_policy

    policy = load_policy(policy_dir)
    torch.manual_seed(0)
    for deterministic in (True, False):
        wins = 0
        for episode in range(episodes):
            env = HexapodEnv.from_params(policy.params, "single_block", obs_sensors=policy.sensors)
            obs, info = env.reset(seed=1000 + episode)  # evaluate's seeds
            done = False
            while not done:
                action, _ = policy.actor.predict(policy.normaliser(policy.features(obs)), deterministic=deterministic)
                obs, _, terminated, truncated, info = env.step(np.asarray(action).reshape(-1))
                done = terminated or truncated
            wins += info["termination"] == "goal"
            env.close()
        print(f"{policy_dir} single_block, {'deterministic' if deterministic else 'stochastic'}: {wins}/{episodes}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--policy", help="a trained policy folder (train-ppo's ppo.out_dir)")
    parser.add_argument("--episodes", type=int, default=10)
    args = parser.parse_args()
    trials()
    if args.policy:
        acting(args.policy, args.episodes)
