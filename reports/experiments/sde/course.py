"""Shared by this folder's scripts: run a sweep's policy along a course and bin what it did by the base's distance."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator

import numpy as np

import hexpipe
from hexpipe.envs.hexapod import HexapodEnv

BIN = 0.2  # m of base distance per bin
Record = Callable[[HexapodEnv, dict, dict], tuple[float, ...]]  # (env, obs, info) after a step -> one row


def episodes(policy_dir: str, terrain: str, count: int, record: Record) -> Iterator[tuple[str, np.ndarray]]:
    """Per episode (deterministic, evaluate's seeds 1000, 1001, ...): how it ended and its rows, one per step, each
    starting with the base's distance (m)."""
    policy = hexpipe.load_policy(policy_dir)
    env = HexapodEnv.from_params(policy.params, terrain, obs_sensors=policy.sensors)
    try:
        for episode in range(count):
            obs, info = env.reset(seed=1000 + episode)
            rows, done = [], False
            while not done:
                obs, _, terminated, truncated, info = env.step(policy.predict(obs))
                done = terminated or truncated
                rows.append((info["distance"], *record(env, obs, info)))
            yield info["termination"], np.array(rows)
    finally:
        env.close()


def bins(rows: np.ndarray) -> Iterator[tuple[float, np.ndarray]]:
    """(lower edge, rows whose distance falls in [edge, edge + BIN)) for every bin of the 3 m course."""
    for lo in np.arange(0.0, 3.0, BIN):
        yield float(lo), rows[(rows[:, 0] >= lo) & (rows[:, 0] < lo + BIN)]


def main(run: Callable[[str, str, int], None], doc: str | None) -> None:
    """POLICY_DIR [TERRAIN] [EPISODES] from the command line (default extra_blocks, 3 episodes)."""
    if len(sys.argv) < 2:
        raise SystemExit(doc)
    run(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else "extra_blocks", int(sys.argv[3]) if len(sys.argv) > 3 else 3)
