"""How much of a training distribution's course is open ground: where task.lift_free_zone charges the lift price
(no relief over 3 cm from 0.6 m behind to 0.7 m ahead of the base, the reward's own test) and so where the lift
reflex, and with it task.lift_teacher, asks for b's floor.

    .venv/bin/python reports/experiments/open/open_ground.py varied varied_open   # or a terrain file

Draws 2000 courses per terrain at difficulty 0.7 (about where the curriculum ends in 120k steps) from one seeded
generator and samples the base's x every 5 cm over the 3 m from the start (x = 0) to the goal, on the centre line.
"""

import sys

import numpy as np

from hexpipe.envs.rewards import lift_waived
from hexpipe.sim.terrain import load_terrain, realize

DRAWS, DIFFICULTY, ZONE = 2000, 0.7, (0.6, 0.7)
XS = np.arange(0.0, 3.0, 0.05)

for name in sys.argv[1:] or ["varied"]:
    recipe, rng = load_terrain(name), np.random.default_rng(0)
    open_share = []
    for _ in range(DRAWS):
        terrain = realize(recipe, rng, DIFFICULTY)
        charged = [not lift_waived(terrain.relief(float(x), 0.0, 0.0, *ZONE)) for x in XS]
        open_share.append(np.mean(charged))
    share = np.asarray(open_share)
    none, full = np.mean(share == 0), np.mean(share == 1)
    print(f"{name}: open ground {share.mean():.3f} of the course on average; ", end="")
    print(f"courses with none {none:.3f}, all open {full:.3f}")
