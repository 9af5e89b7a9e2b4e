"""Is the numpy rollout forward SB3's arithmetic? Train 2048 steps twice from the same seed, once with torch's
forward and once with the numpy one fed torch's own noise, record every step PPO stores, and print the largest
difference per step: observation, action, value and log-probability agree to rounding until the physics
amplifies it.

    .venv/bin/python reports/experiments/rollout_equivalence.py /tmp/equivalence
"""

import subprocess
import sys
from pathlib import Path

import numpy as np

CHILD = r'''
import sys, numpy as np, torch
from pathlib import Path
import hexpipe.rl.rollout as R
from stable_baselines3.common.buffers import RolloutBuffer
out, forward = Path(sys.argv[1]), sys.argv[2]
if forward == "numpy":  # torch's noise, drawn exactly as torch.normal(mean, std) draws it
    def sample(mean, log_std, rng, deterministic=False):
        noise = torch.randn(mean.shape).numpy()
        log_prob = (-0.5 * noise**2 - log_std - R.HALF_LOG_2PI).sum(axis=1)
        return (mean + np.exp(log_std) * noise).astype(np.float32), log_prob.astype(np.float32)
    R.gaussian_sample = sample
    R.NumpyRollout._rng = np.random.default_rng(0)  # no draw from torch's generator for the seed
rows, add = [], RolloutBuffer.add
def record(self, obs, action, reward, start, value, log_prob):
    rows.append(np.concatenate([np.ravel(obs), np.ravel(action), np.ravel(reward),
                                value.numpy().ravel(), log_prob.numpy().ravel()]))
    return add(self, obs, action, reward, start, value, log_prob)
RolloutBuffer.add = record
from hexpipe.config import load_params
from hexpipe.rl.train import train_ppo
params = load_params(Path("params.yaml"), ["ppo.total_timesteps=2048", f"ppo.out_dir={out}/ppo",
    f"ppo.report_dir={out}/reports", "ppo.checkpoint_every=100000", f"ppo.rollout_forward={forward}"])
train_ppo(params, show_progress=False)
np.save(out / "steps.npy", np.stack(rows))
'''


def main() -> None:
    root = Path(sys.argv[1])
    for forward in ("torch", "numpy"):
        (root / forward).mkdir(parents=True, exist_ok=True)
        subprocess.run([sys.executable, "-c", CHILD, str(root / forward), forward], check=True)
    a, b = (np.load(root / f / "steps.npy") for f in ("torch", "numpy"))
    gap = np.abs(a - b).max(axis=1)
    diverged = int(np.argmax(gap > 1e-5))
    print(f"largest difference over the first {diverged} steps: {gap[:diverged].max():.1e}; "
          f"above 1e-5 from step {diverged}; at step 100: {gap[100]:.1e}")


if __name__ == "__main__":
    main()
