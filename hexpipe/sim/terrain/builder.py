"""The PyBullet side of a terrain: create a `Terrain` as static bodies in a client (the only module here that
imports PyBullet)."""

from __future__ import annotations

from collections.abc import Sequence

from hexpipe.sim.terrain.model import Rgba, Terrain

GREY: Rgba = (0.6, 0.6, 0.6, 1.0)  # ground plane
GROUND_HALF_EXTENT = 20.0  # the ground plane is a 40 m x 40 m static box centred on the origin (m)
GROUND_THICKNESS = 0.1  # (m); its top is z = 0


def build_terrain(terrain: Terrain, client: int) -> list[int]:
    """Create `terrain` as static bodies in PyBullet client `client`; returns their body ids.

    The ground is a thin 40 m x 40 m grey box with its top at z = 0. Height fields are placed with
    PyBullet's convention in mind: the shape is centred on its grid midpoint in x and y and on the
    midpoint of its min and max height in z, and the flat data is x-fastest (Fortran order).
    """
    import pybullet as p

    ids: list[int] = []

    def add_box(center: Sequence[float], half: Sequence[float], yaw: float, rgba: Sequence[float]) -> None:
        col = p.createCollisionShape(p.GEOM_BOX, halfExtents=list(half), physicsClientId=client)
        vis = p.createVisualShape(p.GEOM_BOX, halfExtents=list(half), rgbaColor=list(rgba), physicsClientId=client)
        ids.append(
            p.createMultiBody(
                baseMass=0,
                baseCollisionShapeIndex=col,
                baseVisualShapeIndex=vis,
                basePosition=list(center),
                baseOrientation=p.getQuaternionFromEuler([0.0, 0.0, yaw]),
                physicsClientId=client,
            )
        )

    g = GROUND_HALF_EXTENT
    add_box((0.0, 0.0, -GROUND_THICKNESS / 2), (g, g, GROUND_THICKNESS / 2), 0.0, GREY)
    for b in terrain.boxes:
        add_box(b.center, [s / 2 for s in b.size], b.yaw, b.rgba)
    for hf in terrain.heightfields:
        nx, ny = hf.heights.shape
        lo, hi = float(hf.heights.min()), float(hf.heights.max())
        col = p.createCollisionShape(
            p.GEOM_HEIGHTFIELD,
            meshScale=[hf.cell, hf.cell, 1.0],
            heightfieldData=hf.heights.ravel(order="F").tolist(),
            numHeightfieldRows=nx,
            numHeightfieldColumns=ny,
            physicsClientId=client,
        )
        (x0, x1), (y0, y1) = hf.extent
        body = p.createMultiBody(
            baseMass=0,
            baseCollisionShapeIndex=col,
            basePosition=[(x0 + x1) / 2, (y0 + y1) / 2, (lo + hi) / 2],
            physicsClientId=client,
        )
        # No visual shape: PyBullet draws the collision mesh (also in TinyRenderer); just colour it.
        p.changeVisualShape(body, -1, rgbaColor=list(hf.rgba), physicsClientId=client)
        ids.append(body)
    if terrain.friction is not None:
        for body in ids:
            p.changeDynamics(body, -1, lateralFriction=terrain.friction, physicsClientId=client)
    return ids
