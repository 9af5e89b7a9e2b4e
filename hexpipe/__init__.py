"""hexpipe: terrain-adaptive CPG gaits for an 18-DoF hexapod, from rollouts to PPO, as a DVC pipeline."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import TYPE_CHECKING

import gymnasium

try:
    __version__ = version("hexpipe")
except PackageNotFoundError:  # running from a source tree without install
    __version__ = "0.0.0+local"

ENV_ID = "hexpipe/Hexapod-v0"

if ENV_ID not in gymnasium.registry:
    gymnasium.register(ENV_ID, entry_point="hexpipe.envs.hexapod:HexapodEnv")


if TYPE_CHECKING:
    from hexpipe.config import Params
    from hexpipe.rl.policy import LoadedPolicy


def load_policy(policy_dir: str | Path, params: Params | None = None) -> LoadedPolicy:
    """The policy train-ppo wrote to `policy_dir` (ppo.out_dir), ready to run: `policy.predict(obs) -> action`.

    Loads weights-only files (no pickle). `policy.env_kwargs` builds an env with the settings it was trained with
    (or `params`, checked against them). Raises `hexpipe.rl.policy.PolicyError` (one line) if it cannot.
    """
    from hexpipe.rl.policy import load_policy as _load

    return _load(policy_dir, params)
