"""One open-loop episode of a fixed CPG gait (zero action): the building block of the premise and suite checks."""

from __future__ import annotations

import math

import numpy as np

from hexpipe.config import CpgConfig, SimConfig, TaskConfig
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.envs.rewards import cost_of_transport
from hexpipe.sim.terrain import TerrainRecipe


def fixed_gait_episode(terrain: str | TerrainRecipe, a: float, b: float, seed: int, sim: SimConfig | None = None,
                       omega: float = 1.5 * math.pi) -> dict:
    """Walk (a, b, omega) until the episode ends; one row: termination, distance (m), time (s), cost of transport."""
    gait = (a, b, omega)
    env = HexapodEnv(terrain, sim=sim, cpg=CpgConfig().holding(gait), initial_cpg=gait, task=TaskConfig(sensors=()))
    env.reset(seed=seed)
    while True:
        _, _, terminated, truncated, info = env.step(np.zeros(3))
        if terminated or truncated:
            env.close()
            cot = cost_of_transport(info["energy"], env.robot_spec.total_mass, info["distance"])
            name = terrain if isinstance(terrain, str) else terrain.name
            return {"terrain": name, "a": a, "b": b, "seed": seed, "termination": info["termination"],
                    "distance_m": round(info["distance"], 3), "time_s": round(info["time"], 2),
                    "cost_of_transport": round(cot, 2)}
