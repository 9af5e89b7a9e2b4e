"""What only the critic sees (`ppo.privileged_critic`): the true terrain under and ahead of the robot, and the physics
drawn at reset.

An asymmetric actor-critic (Pinto et al. 2018; legged_gym's `privileged_obs`) trains the value function on
information the policy will not have when it runs. The critic's estimate of what a state is worth (how much climbing
and how large a failure penalty lie ahead, how slippery the floor is) then stops being a guess from the 8-d
embedding, which lowers the variance of the advantages the actor learns from. Nothing here reaches the actor: the
exported policy takes the same inputs as without it.
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from hexpipe.config import SensorConfig
from hexpipe.sensors.heightmap import LIMIT_M

PRIVILEGED = "privileged"  # the observation key
CORRIDOR_M = 0.4  # half-width (m) of the strip the legs walk in: the profile's max is taken across it
PHYSICS = ("friction", "mass_scale")  # drawn at reset under ppo.randomize (1.0 mass scale otherwise)


def privileged_size(sensors: SensorConfig) -> int:
    """Length of the privileged vector: one height per height-map row, then the physics."""
    return sensors.heightmap_rows + len(PHYSICS)


def privileged_space(sensors: SensorConfig) -> spaces.Box:
    """Heights within the height map's bound (m); friction and mass scale are positive and far below it."""
    return spaces.Box(-LIMIT_M, LIMIT_M, shape=(privileged_size(sensors),), dtype=np.float32)


def corridor_columns(sensors: SensorConfig) -> np.ndarray:
    """Boolean mask of the height-map columns whose centre lies within CORRIDOR_M of the heading line (every column
    when none does: a coarse map of few, wide cells)."""
    cell = sensors.heightmap_width / sensors.heightmap_cols
    centres = -sensors.heightmap_width / 2 + cell * (np.arange(sensors.heightmap_cols) + 0.5)
    inside = np.abs(centres) <= CORRIDOR_M
    return inside if inside.any() else np.ones_like(inside)


def privileged_vector(
    heightmap: np.ndarray, friction: float, mass_scale: float, sensors: SensorConfig, columns: np.ndarray | None = None
) -> np.ndarray:
    """(rows + 2,) float32: the highest terrain (m above the stance plane) in each height-map row across the legs'
    corridor, from the map's near edge (behind the hind feet) to its far edge, then friction and the base-mass scale.

    heightmap: one reading, (rows, cols) or flattened, as the height-map sensor gives it.
    columns: corridor_columns(sensors), passed by a caller that computed it once.
    """
    grid = np.asarray(heightmap, dtype=np.float32).reshape(sensors.heightmap_rows, sensors.heightmap_cols)
    profile = grid[:, corridor_columns(sensors) if columns is None else columns].max(axis=1)
    vector = np.concatenate([profile, np.array([friction, mass_scale], dtype=np.float32)])
    return np.clip(vector, -LIMIT_M, LIMIT_M).astype(np.float32)
