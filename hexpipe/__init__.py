"""hexpipe: terrain-adaptive CPG gaits for an 18-DoF hexapod, from rollouts to PPO, as a DVC pipeline."""

from importlib.metadata import PackageNotFoundError, version

import gymnasium

try:
    __version__ = version("hexpipe")
except PackageNotFoundError:  # running from a source tree without install
    __version__ = "0.0.0+local"

ENV_ID = "hexpipe/Hexapod-v0"

if ENV_ID not in gymnasium.registry:
    gymnasium.register(ENV_ID, entry_point="hexpipe.envs.hexapod:HexapodEnv")
