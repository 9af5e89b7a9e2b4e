"""Foot contacts: per leg, whether the foot link touches anything and the normal force on it (N).

Read from PyBullet's contact points of each leg's lower link (the shin capsule and its foot sphere) after the last
physics substep, legs in the robot's order (`RobotSpec.legs`). Optional in the observation (`task.sensors`),
logged to MCAP on every kept step; the evaluation's gait diagram (stance and swing per leg over time) reads it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from hexpipe.sensors.base import Message, Sensor, SimView

if TYPE_CHECKING:
    from hexpipe.config import SensorConfig

LEGS = 6
MAX_FORCE_N = 1e4  # observation bound; the whole robot weighs about 200 N
_NORMAL = 7  # index of contactNormalOnB in a getContactPoints tuple
_NORMAL_FORCE = 9  # index of the normal force in a getContactPoints tuple


def _contact_points(client: int, body: int, link: int) -> tuple:
    """The link's contact points, PyBullet tuples with the robot as body A."""
    import pybullet as p

    return p.getContactPoints(bodyA=body, linkIndexA=link, physicsClientId=client)


def read_contacts(client: int, body: int, links: list[int]) -> np.ndarray:
    """(2, legs) float32: row 0 is 1 where a link has a contact point pressing with a positive normal force, row 1
    the summed normal force (N) on it."""
    out = np.zeros((2, len(links)), dtype=np.float32)
    for leg, link in enumerate(links):
        force = sum(point[_NORMAL_FORCE] for point in _contact_points(client, body, link))
        out[0, leg] = float(force > 0.0)
        out[1, leg] = force
    return out


def contact_normals(client: int, body: int, links: list[int]) -> list[np.ndarray]:
    """Per link, a (points, 3) array of the unit normals of its contact points that press (positive normal force),
    each pointing from what it touches towards the robot (PyBullet's contactNormalOnB with the robot as body A)."""
    return [np.array([point[_NORMAL] for point in _contact_points(client, body, link) if point[_NORMAL_FORCE] > 0.0],
                     dtype=float).reshape(-1, 3) for link in links]


class FootContacts(Sensor):
    name = "contacts"
    topic = "/contacts"
    kind = "json"

    def frame_shape(self, cfg: SensorConfig) -> tuple[int, ...]:
        return (2, LEGS)

    def space(self, cfg: SensorConfig):
        from gymnasium import spaces

        high = np.concatenate([np.ones(LEGS), np.full(LEGS, MAX_FORCE_N)]).astype(np.float32)
        return spaces.Box(np.zeros(2 * LEGS, dtype=np.float32), high)

    def reader(self, cfg: SensorConfig):
        def read(view: SimView) -> np.ndarray:
            out = read_contacts(view.client, view.robot.body, view.robot.foot_links)
            out[1] = np.minimum(out[1], MAX_FORCE_N)
            return out

        return read

    def observation(self, reading: np.ndarray) -> np.ndarray:
        return reading.reshape(-1)  # 6 contact flags, then 6 normal forces (N)

    def message(self, reading: np.ndarray, cfg: SensorConfig) -> Message:
        payload = {"contact": [bool(c) for c in reading[0]], "force": [float(f) for f in reading[1]]}
        return Message(self.topic, self.kind, payload, schema="hexpipe.FootContacts")

    def decode(self, payload: Any) -> np.ndarray:
        return np.array([payload["contact"], payload["force"]], dtype=np.float32)
