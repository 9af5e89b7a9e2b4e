"""Where and how a trained policy stops on single_block: per episode, where the base ended, the CPG's lift b and
stride a over its last 2 s, b while the base crossed the block's rear edge, and where each leg group's feet stood.

    .venv/bin/python reports/experiments/collapse_trace.py POLICY_DIR [POLICY_DIR ...] --episodes 5

A foot counts as "on top" when it stands within the block's forward extent above half its height; "past" when it
is beyond the block's rear edge. Evaluate's episode seeds (1000, 1001, ...) and the deterministic action.
"""

import argparse
from pathlib import Path

import numpy as np

from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.evaluation.episodes import _box_spans
from hexpipe.rl.policy import load_policy

LAST_S = 2.0  # the window (s) at the episode's end over which a, b are averaged
REAR_EDGE_M = 0.3  # b is averaged while the base is within this far past the block's rear edge (m)


def feet_where(env: HexapodEnv, span: tuple[float, float], height: float) -> str:
    """Leg group -> where its feet are: 'before', 'top', 'past' (joined by '/' where a group's feet differ)."""
    feet = env.robot.foot_positions()
    x = feet[:, 0] - float(env.start_xy[0])
    where = np.where(x > span[1], "past", np.where((x >= span[0]) & (feet[:, 2] > height / 2), "top", "before"))
    groups: dict[str, list[str]] = {}
    for leg, w in zip(env.robot_spec.legs, where, strict=True):
        groups.setdefault(leg.group, []).append(str(w))
    return " ".join(f"{g}:{'/'.join(sorted(set(ws)))}" for g, ws in groups.items())


def episode(policy, seed: int) -> str:
    env = HexapodEnv.from_params(policy.params, "single_block", obs_sensors=policy.sensors)
    obs, info = env.reset(seed=seed)
    (face, rear), = _box_spans(env)
    height = float(env.terrain.boxes[0].size[2])
    trace, done = [], False
    while not done:
        obs, _, terminated, truncated, info = env.step(policy.predict(obs))
        trace.append((info["distance"], *info["cpg"]))
        done = terminated or truncated
    trace = np.array(trace)
    last = trace[-max(1, round(LAST_S / env.control_dt)):]
    edge = trace[(trace[:, 0] > rear) & (trace[:, 0] <= rear + REAR_EDGE_M), 2]
    ended = info["termination"] or "time limit"
    out = (f"  seed {seed}: {ended:5s} at {info['distance']:.2f} m (block {face:.1f}-{rear:.1f} m); "
           f"last {LAST_S:.0f} s: a {last[:, 1].mean():.2f} b {last[:, 2].mean():.2f}; "
           f"b over the rear edge {edge.mean() if len(edge) else float('nan'):.2f}; "
           f"feet {feet_where(env, (face, rear), height)}")
    env.close()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("policies", nargs="+", help="trained policy folders (train-ppo's ppo.out_dir)")
    parser.add_argument("--episodes", type=int, default=5)
    args = parser.parse_args()
    for folder in args.policies:
        print(Path(folder))
        policy = load_policy(folder)
        for i in range(args.episodes):
            print(episode(policy, 1000 + i))


if __name__ == "__main__":
    main()
