"""A HEBI-Daisy-like 18-DoF hexapod: its dimensions, the URDF generated from them, and PD joint control.

Figures follow HEBI's published Daisy description (hebi_description, `Daisy.hrdf`): legs 1, 2, 5, 6 mounted at
0.2375 m and +-30 / +-150 deg, legs 3, 4 at 0.1875 m and +-90 deg, 5.0 kg chassis, per leg an X8-9 hip yaw
(0.48 kg, 20 N m), a bracket (0.215 kg), an X8-16 shoulder (0.50 kg, 38 N m), a 0.325 m link, an X8-9 elbow
(0.48 kg, 20 N m), a 0.325 m link and a foot (0.06 kg): about 20 kg in all.

Joint conventions (used by `hexpipe.sim.gait`):
- hip yaw: axis +z, positive turns the leg counter-clockwise seen from above;
- shoulder and elbow: axis -y of the leg frame (x outward, z up), so a positive angle raises the link.
"""

from __future__ import annotations

import hashlib
import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hexpipe.atomic import atomic_path


@dataclass(frozen=True)
class LegMount:
    name: str
    angle: float  # mount direction in the base frame (rad, CCW from +x)
    radius: float  # distance of the hip yaw axis from the base centre (m)
    tripod: int  # 0 or 1: legs of one tripod swing together

    @property
    def group(self) -> str:
        """`front`, `middle` or `hind`, from the mount direction (the middle pair points sideways)."""
        ahead = math.cos(self.angle)
        return "front" if ahead > 0.5 else "hind" if ahead < -0.5 else "middle"


def _daisy_legs() -> tuple[LegMount, ...]:
    deg = math.radians
    return (
        LegMount("leg1", deg(30), 0.2375, 0),  # left front
        LegMount("leg2", deg(-30), 0.2375, 1),  # right front
        LegMount("leg3", deg(90), 0.1875, 1),  # left middle
        LegMount("leg4", deg(-90), 0.1875, 0),  # right middle
        LegMount("leg5", deg(150), 0.2375, 0),  # left back
        LegMount("leg6", deg(-150), 0.2375, 1),  # right back
    )


@dataclass(frozen=True)
class RobotSpec:
    """Geometry (m), masses (kg), joint limits (rad) and actuator limits (N m) of the hexapod."""

    legs: tuple[LegMount, ...] = field(default_factory=_daisy_legs)
    chassis_size: tuple[float, float, float] = (0.42, 0.30, 0.08)
    chassis_mass: float = 5.0
    bracket_length: float = 0.05  # hip yaw axis -> shoulder axis, outward
    upper_length: float = 0.325
    lower_length: float = 0.325
    link_radius: float = 0.025  # collision capsule radius of the leg links
    foot_radius: float = 0.02
    hip_mass: float = 0.48 + 0.215 + 0.50  # X8-9 yaw + bracket + X8-16 shoulder
    upper_mass: float = 0.40 + 0.48  # link + X8-9 elbow
    lower_mass: float = 0.40 + 0.06  # link + foot
    yaw_limit: tuple[float, float] = (-0.8, 0.8)  # keeps neighbouring legs apart
    shoulder_limit: tuple[float, float] = (-1.2, 1.6)
    elbow_limit: tuple[float, float] = (-2.9, 0.5)
    yaw_effort: float = 20.0  # X8-9 continuous torque (N m)
    shoulder_effort: float = 38.0  # X8-16
    elbow_effort: float = 20.0  # X8-9
    yaw_speed: float = 3.14  # datasheet speed (rad/s); enforced by slew-limiting joint targets
    shoulder_speed: float = 1.57
    elbow_speed: float = 3.14

    @property
    def joint_names(self) -> list[str]:
        return [f"{leg.name}_{j}" for leg in self.legs for j in ("yaw", "shoulder", "elbow")]

    @property
    def link_names(self) -> list[str]:
        """Child link of each joint, in PyBullet link-index order."""
        return [f"{leg.name}_{j}" for leg in self.legs for j in ("hip", "upper", "lower")]

    @property
    def efforts(self) -> np.ndarray:
        return np.tile([self.yaw_effort, self.shoulder_effort, self.elbow_effort], len(self.legs))

    @property
    def speeds(self) -> np.ndarray:
        return np.tile([self.yaw_speed, self.shoulder_speed, self.elbow_speed], len(self.legs))

    @property
    def total_mass(self) -> float:
        return self.chassis_mass + len(self.legs) * (self.hip_mass + self.upper_mass + self.lower_mass)


@dataclass(frozen=True)
class LinkShape:
    """A visual primitive fixed to a link frame (for viewers such as Foxglove), in that frame's coordinates."""

    link: str
    kind: str  # "cube", "cylinder" (axis along +x of the link) or "sphere"
    position: tuple[float, float, float]
    size: tuple[float, float, float]  # full extents (m)
    rgba: tuple[float, float, float, float]


def robot_shapes(spec: RobotSpec) -> list[LinkShape]:
    """The robot's visual geometry per link, matching the URDF."""
    shapes = [LinkShape("base_link", "cube", (0.0, 0.0, 0.0), spec.chassis_size, (0.8, 0.3, 0.1, 1.0))]
    grey = (0.3, 0.3, 0.35, 1.0)
    for leg in spec.legs:
        b, u, lo = spec.bracket_length, spec.upper_length, spec.lower_length
        r = spec.link_radius
        shapes += [
            LinkShape(f"{leg.name}_hip", "cube", (b / 2, 0.0, 0.0), (b, 0.08, 0.08), (0.2, 0.2, 0.2, 1.0)),
            LinkShape(f"{leg.name}_upper", "cylinder", (u / 2, 0.0, 0.0), (u, 2 * r, 2 * r), grey),
            LinkShape(f"{leg.name}_lower", "cylinder", (lo / 2, 0.0, 0.0), (lo, 1.6 * r, 1.6 * r), (0.6, 0.6, 0.65, 1.0)),
            LinkShape(f"{leg.name}_lower", "sphere", (lo, 0.0, 0.0), (2 * spec.foot_radius,) * 3, (0.1, 0.1, 0.1, 1.0)),
        ]
    return shapes


def _inertial(mass: float, size: tuple[float, float, float], xyz: str = "0 0 0") -> str:
    sx, sy, sz = size
    ixx, iyy, izz = (mass / 12 * (sy**2 + sz**2), mass / 12 * (sx**2 + sz**2), mass / 12 * (sx**2 + sy**2))
    return (
        f'<inertial><origin xyz="{xyz}"/><mass value="{mass}"/>'
        f'<inertia ixx="{ixx:.6g}" iyy="{iyy:.6g}" izz="{izz:.6g}" ixy="0" ixz="0" iyz="0"/></inertial>'
    )


def _capsule_link(name: str, mass: float, length: float, radius: float, rgba: str, foot: float = 0.0) -> str:
    """A link whose body runs along +x from its joint, a cylinder with collision (so block edges catch the shin)."""
    half = length / 2
    geom = f'<origin xyz="{half} 0 0" rpy="0 {math.pi / 2} 0"/><geometry><cylinder radius="{radius}" length="{length}"/></geometry>'
    # Visuals are boxes: the body camera's TinyRenderer cost grows with triangles, and cylinders and spheres
    # have hundreds each. Collision keeps the round shapes.
    box = f'<origin xyz="{half} 0 0"/><geometry><box size="{length} {2 * radius} {2 * radius}"/></geometry>'
    foot_xml = ""
    if foot:
        foot_xml = (
            f'<collision><origin xyz="{length} 0 0"/><geometry><sphere radius="{foot}"/></geometry></collision>'
            f'<visual><origin xyz="{length} 0 0"/><geometry><box size="{2 * foot} {2 * foot} {2 * foot}"/></geometry>'
            f'<material name="foot"><color rgba="0.1 0.1 0.1 1"/></material></visual>'
        )
    return (
        f'<link name="{name}">{_inertial(mass, (length, 2 * radius, 2 * radius), f"{half} 0 0")}'
        f'<visual>{box}<material name="{name}_m"><color rgba="{rgba}"/></material></visual>'
        f"<collision>{geom}</collision>{foot_xml}</link>"
    )


def robot_urdf(spec: RobotSpec) -> str:
    """The URDF text for `spec`: base_link plus, per leg, hip (yaw), upper (shoulder) and lower (elbow) links."""
    cx, cy, cz = spec.chassis_size
    parts = [
        '<?xml version="1.0"?><robot name="hexpipe_daisy">',
        f'<link name="base_link">{_inertial(spec.chassis_mass, spec.chassis_size)}'
        f'<visual><geometry><box size="{cx} {cy} {cz}"/></geometry>'
        f'<material name="chassis"><color rgba="0.8 0.3 0.1 1"/></material></visual>'
        f'<collision><geometry><box size="{cx} {cy} {cz}"/></geometry></collision></link>',
    ]
    for leg in spec.legs:
        x, y = leg.radius * math.cos(leg.angle), leg.radius * math.sin(leg.angle)
        hip = f"{leg.name}_hip"
        parts.append(
            f'<link name="{hip}">{_inertial(spec.hip_mass, (spec.bracket_length, 0.1, 0.1), f"{spec.bracket_length / 2} 0 0")}'
            f'<visual><origin xyz="{spec.bracket_length / 2} 0 0"/><geometry><box size="{spec.bracket_length} 0.08 0.08"/></geometry>'
            f'<material name="{hip}_m"><color rgba="0.2 0.2 0.2 1"/></material></visual></link>'
        )
        parts.append(
            f'<joint name="{leg.name}_yaw" type="revolute"><parent link="base_link"/><child link="{hip}"/>'
            f'<origin xyz="{x:.6f} {y:.6f} 0" rpy="0 0 {leg.angle:.6f}"/><axis xyz="0 0 1"/>'
            f'<limit lower="{spec.yaw_limit[0]}" upper="{spec.yaw_limit[1]}" effort="{spec.yaw_effort}" velocity="{spec.yaw_speed}"/></joint>'
        )
        parts.append(_capsule_link(f"{leg.name}_upper", spec.upper_mass, spec.upper_length, spec.link_radius, "0.3 0.3 0.35 1"))
        parts.append(
            f'<joint name="{leg.name}_shoulder" type="revolute"><parent link="{hip}"/><child link="{leg.name}_upper"/>'
            f'<origin xyz="{spec.bracket_length} 0 0"/><axis xyz="0 -1 0"/>'
            f'<limit lower="{spec.shoulder_limit[0]}" upper="{spec.shoulder_limit[1]}" effort="{spec.shoulder_effort}" velocity="{spec.shoulder_speed}"/></joint>'
        )
        parts.append(
            _capsule_link(
                f"{leg.name}_lower", spec.lower_mass, spec.lower_length, spec.link_radius * 0.8, "0.6 0.6 0.65 1",
                foot=spec.foot_radius,
            )
        )
        parts.append(
            f'<joint name="{leg.name}_elbow" type="revolute"><parent link="{leg.name}_upper"/><child link="{leg.name}_lower"/>'
            f'<origin xyz="{spec.upper_length} 0 0"/><axis xyz="0 -1 0"/>'
            f'<limit lower="{spec.elbow_limit[0]}" upper="{spec.elbow_limit[1]}" effort="{spec.elbow_effort}" velocity="{spec.elbow_speed}"/></joint>'
        )
    parts.append("</robot>")
    return "\n".join(parts)


def urdf_path(spec: RobotSpec) -> Path:
    """Write the URDF once per distinct spec into the temp dir (content-addressed, so processes can share it)."""
    text = robot_urdf(spec)
    digest = hashlib.sha1(text.encode()).hexdigest()[:12]
    path = Path(tempfile.gettempdir()) / f"hexpipe_daisy_{digest}.urdf"
    if not path.exists():
        with atomic_path(path, shared=True) as tmp:  # other processes may be writing the same file
            tmp.write_text(text)
    return path


class Robot:
    """The hexapod inside one PyBullet client: loading, state reads and PD position control."""

    def __init__(self, client: int, spec: RobotSpec, base_position, base_orientation=(0, 0, 0, 1)):
        import pybullet as p

        self._p = p
        self.client = client
        self.spec = spec
        self.body = p.loadURDF(
            str(urdf_path(spec)), base_position, base_orientation, useFixedBase=False,
            flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=client,
        )
        self.joints = list(range(p.getNumJoints(self.body, physicsClientId=client)))
        self._efforts = spec.efforts.tolist()
        self.foot_links = [self.joints[i] for i in range(2, len(self.joints), 3)]

    def set_friction(self, friction: float) -> None:
        for link in [-1, *self.joints]:
            self._p.changeDynamics(self.body, link, lateralFriction=friction, physicsClientId=self.client)

    def scale_base_mass(self, scale: float) -> None:
        self._p.changeDynamics(self.body, -1, mass=self.spec.chassis_mass * scale, physicsClientId=self.client)

    def reset_joints(self, positions: np.ndarray) -> None:
        for j, q in zip(self.joints, positions, strict=True):
            self._p.resetJointState(self.body, j, float(q), 0.0, physicsClientId=self.client)

    def command(self, targets: np.ndarray, position_gain: float, velocity_gain: float) -> None:
        """PD position control towards `targets` (rad), torque clipped at each actuator's effort limit."""
        n = len(self.joints)
        self._p.setJointMotorControlArray(
            self.body, self.joints, self._p.POSITION_CONTROL, targetPositions=targets.tolist(),
            forces=self._efforts, positionGains=[position_gain] * n, velocityGains=[velocity_gain] * n,
            physicsClientId=self.client,
        )

    def base_state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """World position (m), orientation quaternion xyzw, linear (m/s) and angular (rad/s) velocity."""
        pos, orn = self._p.getBasePositionAndOrientation(self.body, physicsClientId=self.client)
        lin, ang = self._p.getBaseVelocity(self.body, physicsClientId=self.client)
        return np.array(pos), np.array(orn), np.array(lin), np.array(ang)

    def joint_states(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions (rad), velocities (rad/s) and applied torques (N m) of the 18 joints."""
        states = self._p.getJointStates(self.body, self.joints, physicsClientId=self.client)
        q, dq, _, tau = zip(*states, strict=True)
        return np.array(q), np.array(dq), np.array(tau)

    def mechanical_power(self) -> float:
        """Sum over the 18 joints of |torque * velocity| (W): what the actuators spend, braking counted as cost."""
        states = self._p.getJointStates(self.body, self.joints, physicsClientId=self.client)
        return float(sum([abs(s[1] * s[3]) for s in states]))  # a list is faster than a generator here

    def foot_positions(self) -> np.ndarray:
        """(legs, 3) world position (m) of each foot's centre: the lower link's far end, where its sphere sits."""
        states = self._p.getLinkStates(self.body, self.foot_links, physicsClientId=self.client)
        reach = np.array([self.spec.lower_length, 0.0, 0.0])
        return np.array([
            np.array(s[4]) + np.array(self._p.getMatrixFromQuaternion(s[5])).reshape(3, 3) @ reach for s in states
        ])

    def link_poses(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """World pose (position, quaternion xyzw) of every link frame, base first."""
        pos, orn = self._p.getBasePositionAndOrientation(self.body, physicsClientId=self.client)
        poses = [(np.array(pos), np.array(orn))]
        for state in self._p.getLinkStates(self.body, self.joints, physicsClientId=self.client):
            poses.append((np.array(state[4]), np.array(state[5])))
        return poses
