"""At gains 0 the elevator and heading reflexes change nothing: a digest of what the env returns.

Run it from two checkouts (before and after the reflexes entered hexpipe/) and compare the printed digests. Each
terrain is walked for `--steps` control steps with seeded random actions in [-1, 1], from reset(seed=i), with the
default params (both gains 0); the digest covers every observation, reward, power and ending, bit for bit.

    PYTHONPATH=. .venv/bin/python reports/experiments/reflexes/gain0.py
    PYTHONPATH=. .venv/bin/python reports/experiments/reflexes/gain0.py --set sim.elevator_gain=2.5   # must differ
"""

from __future__ import annotations

import argparse
import hashlib

import numpy as np

from hexpipe.config import load_params
from hexpipe.envs.hexapod import HexapodEnv

TERRAINS = ("flat", "single_block", "wide_block", "tall_block", "steps_up", "rough")


def digest(terrain: str, steps: int, seed: int, overrides: list[str]) -> tuple[str, str]:
    params = load_params("params.yaml", overrides)
    env = HexapodEnv.from_params(params, terrain, randomize=True)
    rng = np.random.default_rng(seed)
    h = hashlib.sha256()
    obs, _ = env.reset(seed=seed)
    ending = "running"
    for _ in range(steps):
        for value in obs.values() if isinstance(obs, dict) else (obs,):
            h.update(np.ascontiguousarray(value).tobytes())
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-1.0, 1.0, env.action_space.shape))
        h.update(np.float64(reward).tobytes() + np.float64(info["power"]).tobytes())
        if terminated or truncated:
            ending = str(info.get("termination") or "truncated")
            break
    env.close()
    return h.hexdigest()[:16], f"{ending} at {info['distance']:.4f} m"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=400)
    parser.add_argument("--set", action="append", default=[], help="section.key=value (the check that a gain moves it)")
    args = parser.parse_args()
    for i, terrain in enumerate(TERRAINS):
        sha, end = digest(terrain, args.steps, seed=i, overrides=args.set)
        print(f"{terrain:13s} {sha}  {end}")


if __name__ == "__main__":
    main()
