"""What the encoder reads before each face of extra_blocks, where the policy lifts for the first and not the second.

    .venv/bin/python reports/experiments/ceiling/rise_read.py POLICY_DIR [--episodes 10] [--set section.key=value ...]

Runs the policy (deterministic) on evaluate's extra_blocks episodes. While the front feet (FRONT_REACH ahead of the
base) are in the 0.3 m before each face, it averages the true next rise ahead of the base (`terrain_labels`: the
fraction of steps with one in the map's range, and over those, m ahead and m high), the VAE's rise head read from
the policy's own encoder latent (its standardised distance and height, and P(a rise in range)), and b. The head is a
linear readout of the 8-d latent the policy sees, trained with the VAE, so the same head values before both faces
mean the latent carries the second face as it does the first. Rows per episode and face (`steps`: how many control
steps the window held; a stall there holds it long, so a failure's means are mostly the stall's), then the means by
outcome.
"""

from __future__ import annotations

import argparse
import math

import numpy as np
import pandas as pd

from hexpipe.config import ConfigError, load_params
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.evaluation.episodes import BEFORE_FACE, FRONT_REACH
from hexpipe.evaluation.suite import load_scenarios
from hexpipe.models.vae import EncoderError, load_encoder
from hexpipe.rl.policy import PolicyError, load_policy

FACES = (1.0, 2.0)  # m from the start: extra_blocks' two faces


def episode(policy, head, params, index: int) -> list[dict]:
    env = HexapodEnv.from_params(params, load_scenarios(["extra_blocks"])[0].recipe, obs_sensors=policy.sensors)
    obs, info = env.reset(seed=params.eval.seed + index)
    steps, done = [], False
    while not done:
        x = float(env.robot.base_state()[0][0] - env.start_xy[0])
        labels = env.terrain_labels()
        grid = np.asarray(obs["heightmap"]).reshape(1, params.sensors.heightmap_rows, params.sensors.heightmap_cols)
        read = head.encode(grid)[0][-3:]
        steps.append((x, labels["rise_distance"], labels["rise_height"], *read, float(obs["cpg"][1])))
        obs, _, terminated, truncated, info = env.step(policy.predict(obs))
        done = terminated or truncated
    env.close()
    trace = np.asarray(steps)
    success = info["termination"] == "goal"
    rows = []
    for k, face in enumerate(FACES, start=1):
        front = trace[:, 0] + FRONT_REACH
        near = (front >= face - BEFORE_FACE) & (front < face)
        if not near.any():
            continue
        t = trace[near]
        seen = np.isfinite(t[:, 1])  # over a block's top the next face is no rise above the ground under the base
        rows.append({"episode": index, "success": success, "face": k, "steps": int(near.sum()),
                     "true_in_range": float(seen.mean()),
                     "true_m_ahead": float(t[seen, 1].mean()) if seen.any() else math.nan,
                     "true_height": float(t[seen, 2].mean()) if seen.any() else math.nan,
                     "head_distance": t[:, 3].mean(),
                     "head_height": t[:, 4].mean(), "p_rise": float(np.mean(1 / (1 + np.exp(-t[:, 5])))),
                     "b": t[:, 6].mean()})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("policy")
    ap.add_argument("--episodes", type=int, default=10)
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    a = ap.parse_args()
    try:
        params = load_params("params.yaml", overrides=a.overrides)
        policy = load_policy(a.policy, params)
        head = load_encoder(params.ppo.encoder_dir, rise_readout=True)
    except (ConfigError, PolicyError, EncoderError) as exc:
        raise SystemExit(f"error: {exc}") from None
    frame = pd.DataFrame([row for i in range(a.episodes) for row in episode(policy, head, params, i)])
    if frame.empty:
        raise SystemExit(f"error: no episode of {a.policy} brought the front feet to a face")
    with pd.option_context("display.width", 200):
        print(f"{a.policy}: extra_blocks, the front feet in the {BEFORE_FACE} m before each face")
        print(frame.round(3).to_string(index=False))
        print("\nmeans by outcome and face:")
        print(frame.groupby(["success", "face"]).mean(numeric_only=True).drop(columns="episode").round(3).to_string())


if __name__ == "__main__":
    main()
