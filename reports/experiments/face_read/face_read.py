"""What the height map and the encoder read where the default policy fails a face (issue 10, `face_read`).

    .venv/bin/python reports/experiments/face_read/face_read.py [--policy data/models/ppo] [--episodes 4]

Runs the policy (deterministic) on evaluate's episodes (seeds eval.seed onwards, so the rows of
reports/eval/results.csv) and prints:

1. `offset`: the encoder's latent change (Euclidean, 8-d) when the whole first map of an episode (seed 1003) of
   flat, single_block and block_near is shifted by -3..+3 cm, which is what a body held higher or lower does to a
   map read from the stance plane, against the same map moved one row (6.25 cm) nearer.
2. `bob`: per episode of flat and block_near, the standard deviation (cm) of the stance plane's height (base z -
   sim.body_height) above the terrain under the base, the same trace through a first-order low-pass with time
   constants 0.25 and 0.5 s (what a smoothed plane would leave), and the latent's mean step-to-step change.
3. `stall`: the first 3 s of block_near's episode 3 (a failure in the committed evaluation) in 0.2 s samples:
   distance, b, the highest cell of the map's central half-width in the band 0.45-0.75 m ahead of the base (where
   the block's face is while the front feet stand at it), the policy's b action and the latent's change since the
   last sample.
4. `second_face`: per extra_blocks episode, the mean stance plane above the gap's floor while the front feet are
   in the 0.3 m before the second face (x 1.7-2.0 m, the front feet 0.45 m ahead of the base), raw and low-passed
   (0.5 s), so what the map reads the 0.10 m second block as, and the mean b there.
5. with `--sweep DIR` (e.g. reports/sweeps/floorpipe): per trial, the failures on block_near and extra_blocks from
   its evaluation results: b_max (the highest b of the episode) and the distance where it ended.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pandas as pd

from hexpipe.config import ConfigError, Params, load_params
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.evaluation.episodes import FRONT_REACH
from hexpipe.evaluation.suite import load_scenarios
from hexpipe.rl.policy import LoadedPolicy, PolicyError, load_policy

FACE_BAND = (0.45, 0.75)  # m ahead of the base: a face the front feet stand at
TAUS = (0.25, 0.5)  # s


def low_passed(trace: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """A first-order low-pass (time constant tau, s) of a trace sampled every dt s, started at its first value."""
    alpha = 1.0 - math.exp(-dt / tau)
    out = np.empty_like(trace)
    out[0] = trace[0]
    for i in range(1, len(trace)):
        out[i] = out[i - 1] + alpha * (trace[i] - out[i - 1])
    return out


def _grid(obs: dict, params: Params) -> np.ndarray:
    return np.asarray(obs["heightmap"]).reshape(1, params.sensors.heightmap_rows, params.sensors.heightmap_cols)


def _episode(policy: LoadedPolicy, params: Params, terrain: str, index: int) -> dict[str, np.ndarray | str]:
    """One episode's per-step trace: x, the plane above the ground under the base and in world z, b, b action,
    latent, map."""
    env = HexapodEnv.from_params(params, load_scenarios([terrain])[0].recipe, obs_sensors=policy.sensors)
    obs, info = env.reset(seed=params.eval.seed + index)
    rows: dict[str, list] = {k: [] for k in ("x", "plane", "stance", "b", "action_b", "latent", "grid")}
    done = False
    while not done:
        pos = env.robot.base_state()[0]
        ground = float(env.terrain.height_at(pos[:1], pos[1:2])[0])
        action = policy.predict(obs)
        grid = _grid(obs, params)
        rows["x"].append(float(pos[0]))
        rows["plane"].append(float(pos[2]) - params.sim.body_height - ground)
        rows["stance"].append(float(pos[2]) - params.sim.body_height)  # world z of the plane the map reads from
        rows["b"].append(float(obs["cpg"][1]))
        rows["action_b"].append(float(action[1]))
        rows["latent"].append(policy.encoder.encode(grid)[0])
        rows["grid"].append(grid[0])
        obs, _, terminated, truncated, info = env.step(action)
        done = terminated or truncated
    env.close()
    out: dict[str, np.ndarray | str] = {k: np.asarray(v) for k, v in rows.items()}
    out["end"] = info["termination"] or "time"
    return out


def offset(policy: LoadedPolicy, params: Params) -> None:
    print("1. offset: |latent change| for a whole-map shift, against moving the map one row (6.25 cm) nearer")
    for terrain in ("flat", "single_block", "block_near"):
        env = HexapodEnv.from_params(params, load_scenarios([terrain])[0].recipe, obs_sensors=policy.sensors)
        obs, _ = env.reset(seed=1003)
        env.close()
        grid = _grid(obs, params)
        base = policy.encoder.encode(grid)[0]
        moved = np.concatenate([grid[:, 1:], grid[:, -1:]], axis=1)
        shifts = "  ".join(f"{cm:+d} cm {np.linalg.norm(policy.encoder.encode(grid + cm / 100)[0] - base):.2f}"
                           for cm in (-3, -2, -1, 1, 2, 3))
        print(f"  {terrain:12s} {shifts}   one row: {np.linalg.norm(policy.encoder.encode(moved)[0] - base):.2f}")


def bob(policy: LoadedPolicy, params: Params, episodes: int) -> None:
    dt = 1.0 / params.sim.control_hz
    print("2. bob: the stance plane above the terrain under the base, std over the episode (cm); the latent's mean "
          "step-to-step change")
    for terrain in ("flat", "block_near"):
        for index in range(episodes):
            ep = _episode(policy, params, terrain, index)
            plane = ep["plane"]
            smooth = "  ".join(f"tau {tau} s {np.std(low_passed(plane, dt, tau)) * 100:.2f}" for tau in TAUS)
            step = np.linalg.norm(np.diff(ep["latent"], axis=0), axis=1).mean()
            print(f"  {terrain:10s} ep {index}: {ep['end']:5s} {len(plane):3d} steps; plane {np.std(plane) * 100:.2f}"
                  f", low-passed {smooth}; latent step {step:.2f}")


def stall(policy: LoadedPolicy, params: Params) -> None:
    print("3. stall: block_near episode 3, every 0.2 s (map: highest cell 0.45-0.75 m ahead, central half-width)")
    s = params.sensors
    near, far = s.heightmap_ahead
    ahead = near + (np.arange(s.heightmap_rows) + 0.5) * (far - near) / s.heightmap_rows  # each row's centre (m)
    band = (ahead >= FACE_BAND[0]) & (ahead < FACE_BAND[1])
    centre = slice(s.heightmap_cols // 4, 3 * s.heightmap_cols // 4)
    ep = _episode(policy, params, "block_near", 3)
    every = round(0.2 * params.sim.control_hz)
    for i in range(0, min(len(ep["x"]), round(3.0 * params.sim.control_hz) + 1), every):
        change = np.linalg.norm(ep["latent"][i] - ep["latent"][max(i - every, 0)])
        print(f"  t {i / params.sim.control_hz:.1f} s: x {ep['x'][i]:.3f} m, b {ep['b'][i]:.3f}, map "
              f"{ep['grid'][i][band][:, centre].max():.3f} m, b action {ep['action_b'][i]:+.2f}, "
              f"latent moved {change:.2f}")
    print(f"  ends: {ep['end']} after {len(ep['x'])} steps")


def second_face(policy: LoadedPolicy, params: Params, episodes: int) -> None:
    dt = 1.0 / params.sim.control_hz
    print("4. second_face: extra_blocks, front feet in the 0.3 m before the second face (2.0 m)")
    for index in range(episodes):
        ep = _episode(policy, params, "extra_blocks", index)
        front = ep["x"] + FRONT_REACH
        near = (front >= 1.7) & (front < 2.0)
        if not near.any():
            print(f"  ep {index}: {ep['end']}, never reached it")
            continue
        raw, smooth = ep["stance"][near].mean(), low_passed(ep["stance"], dt, 0.5)[near].mean()  # the gap is z 0
        print(f"  ep {index}: {ep['end']:5s} plane above the gap floor {raw:.3f} m (low-passed {smooth:.3f}); "
              f"the 0.10 m block reads {0.1 - raw:.3f} m ({0.1 - smooth:.3f}); mean b {ep['b'][near].mean():.3f}")


def sweep_failures(sweep: Path) -> None:
    print(f"5. failures in {sweep}: b_max and end distance (m) per failed episode")
    for results in sorted(sweep.glob("*/eval/results.csv")):
        rows = pd.read_csv(results)
        rows = rows[(rows.controller == "policy") & ~rows.success]
        for terrain in ("block_near", "extra_blocks"):
            failed = rows[rows.terrain == terrain]
            print(f"  {results.parts[-3]:18s} {terrain:12s} {len(failed):2d} failed; b_max "
                  f"{failed.b_max.round(2).tolist()}; ended at {failed.distance.round(2).tolist()}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--policy", default="data/models/ppo")
    ap.add_argument("--episodes", type=int, default=4)
    ap.add_argument("--sweep", type=Path, help="also list a sweep's block_near and extra_blocks failures")
    args = ap.parse_args()
    if args.sweep is not None and not any(args.sweep.glob("*/eval/results.csv")):
        raise SystemExit(f"error: no trial results (*/eval/results.csv) under {args.sweep}; pass a sweep's reports")
    try:  # a bad params.yaml or policy folder: one line, not a traceback
        params = load_params("params.yaml")
        policy = load_policy(args.policy, params)
    except (ConfigError, PolicyError) as exc:
        raise SystemExit(f"error: {exc}") from None
    if policy.encoder is None:
        raise SystemExit(f"error: {args.policy} is a blind policy; this reads what its terrain encoder sees")
    offset(policy, params)
    bob(policy, params, args.episodes)
    stall(policy, params)
    second_face(policy, params, 2 * args.episodes)
    if args.sweep is not None:
        sweep_failures(args.sweep)


if __name__ == "__main__":
    main()
