"""`hexpipe/Hexapod-v0`: the paper's POMDP. The policy sets the second derivative of the CPG parameters (or, with
`cpg.action_order: 1`, their rate).

Observation (Dict):
- `body` (13): position relative to the start (x, y; z = base height above the terrain below), orientation
  quaternion (xyzw), linear velocity (m/s) and angular velocity (rad/s), world frame; 11 without x, y when
  `TaskConfig.observe_position` is false (the same course shifted along x then looks the same at the same
  distance from its block);
- `cpg` (6): a, b, omega and their rates; 8 with `TaskConfig.observe_phase`, which adds the gait's phase as
  (cos, sin) of leg 0's oscillator, so the policy can time its lift to the legs' swing;
- one entry per sensor named in `TaskConfig.sensors`, as the sensor registry (`hexpipe.sensors`) declares it:
  `heightmap` (rows * cols,) float32 m, row-major; `rgb` (H, W, 3) uint8; `contacts` (12,) per-leg contact
  flags then normal forces (N).
Action: Box [-1, 1]^3, scaled by `CpgConfig.accel_limit` to d^2/dt^2 (a, b, omega), or with `action_order: 1` by
`CpgConfig.rate_limit` to d/dt (a, b, omega). With `TaskConfig.lift_reflex` the legs swing at least as high as a
reflex that reads the height map (hexpipe/sim/lift_reflex.py); `info["lift"]` is the front legs' lift (rad).
With `TaskConfig.lift_teacher` the same reflex runs without moving a leg, and the reward charges b's shortfall
below its lift. With `TaskConfig.stride_teacher` a stride reflex (hexpipe/sim/stride_reflex.py) reads the same map,
and the reward charges a's distance from its stride; with `TaskConfig.stride_reflex` the legs swing with no longer
a stride than that reflex's (a shorter one at the straddle of two blocks); `info["stride"]` is the stride (rad).
Reward: `reward_scale` * forward velocity (m/s, displacement over the control step), as in the paper, minus
`power_cost` * mean mechanical joint power (W) when that is set (0 is the paper's reward), minus `lift_cost` * the lift
b above its floor (rad) when that is set (waived near uneven terrain with `lift_price_zone`, else `lift_free_zone`),
minus `failure_penalty` once when the episode ends stuck or fallen, minus `lift_teacher` * b's shortfall below the
reflex's lift when that is set, minus `stride_teacher` * a's distance from the stride reflex's when that is set,
minus `time_cost` per s of episode time when that is set.
Terminates on `goal` (3 m forward), `stuck` (too little progress over a window), `fall` (tilt or base too low)
or `nonfinite` physics; truncates at the time limit. `info` carries distance, success, termination and the
reward terms.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Iterable
from contextlib import suppress
from functools import partial
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from hexpipe import sensors as registry
from hexpipe.config import CpgConfig, Params, SensorConfig, SimConfig, TaskConfig, reflex_zone
from hexpipe.envs.privileged import PRIVILEGED, corridor_columns, privileged_space, privileged_vector
from hexpipe.envs.rewards import (
    RELIEF_M,
    failure_penalty,
    forward_velocity_reward,
    lift_penalty,
    lift_shortfall_penalty,
    lift_waived,
    power_penalty,
    stride_deviation_penalty,
    time_penalty,
)
from hexpipe.envs.state import WORLD_FRAME, EnvScene, EnvState
from hexpipe.sensors.contacts import contact_normals
from hexpipe.sensors.heightmap import HEADING_FRAME, quat_to_yaw, reference_height
from hexpipe.sim.cpg import CPG
from hexpipe.sim.elevator import caught_legs, elbow_opening, pressed_from_side
from hexpipe.sim.gait import GaitMap, slew_path
from hexpipe.sim.heading import stride_scales
from hexpipe.sim.lift_reflex import lift_reflex
from hexpipe.sim.lift_trail import LiftTrail, foot_lags
from hexpipe.sim.robot import Robot, RobotSpec, robot_shapes
from hexpipe.sim.stride_reflex import stride_reflex
from hexpipe.sim.terrain import Terrain, TerrainRecipe, build_terrain, load_terrain, realize


def quat_to_roll_pitch(q: np.ndarray) -> tuple[float, float]:
    x, y, z, w = q
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    return roll, pitch


def observation_space(cpg: CpgConfig, sensors: SensorConfig, task: TaskConfig, privileged: bool = False) -> spaces.Dict:
    """The observation Dict an env with these settings produces; needs no simulator. privileged: add the critic's
    `privileged` vector (hexpipe/envs/privileged.py)."""
    lo, hi = np.asarray(cpg.lower), np.asarray(cpg.upper)
    rate, fall = np.asarray(cpg.rate_limit), np.asarray(cpg.falling_limit)
    obs: dict[str, spaces.Space] = {
        "body": spaces.Box(-100.0, 100.0, shape=(13 if task.observe_position else 11,), dtype=np.float32),
        "cpg": spaces.Box(
            np.concatenate([lo, -fall, [-1.0, -1.0][:2 * task.observe_phase]]).astype(np.float32),
            np.concatenate([hi, rate, [1.0, 1.0][:2 * task.observe_phase]]).astype(np.float32),
        ),
    }
    for name in task.sensors:
        obs[name] = registry.get(name).space(sensors)
    if privileged:
        obs[PRIVILEGED] = privileged_space(sensors)
    return spaces.Dict(obs)


def _yaw_quaternion(yaw: float) -> np.ndarray:
    return np.array([0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)])


class HexapodEnv(gym.Env):
    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 20}

    def __init__(
        self,
        terrain: str | TerrainRecipe = "single_block",
        sim: SimConfig | None = None,
        cpg: CpgConfig | None = None,
        sensors: SensorConfig | None = None,
        task: TaskConfig | None = None,
        initial_cpg: tuple[float, float, float] | None = None,
        randomize: bool = False,
        render_mode: str | None = None,
        robot: RobotSpec | None = None,
        privileged: bool = False,
    ):
        """privileged: observations also carry `privileged`, the true terrain profile and physics that only an
        asymmetric critic sees in training (ppo.privileged_critic)."""
        import pybullet as p

        self.sim_cfg = sim or SimConfig()
        self.cpg_cfg = cpg or CpgConfig()
        self.sensor_cfg = sensors or SensorConfig()
        self.task = task or TaskConfig()
        self.recipe = load_terrain(terrain) if isinstance(terrain, str) else terrain
        self.robot_spec = robot or RobotSpec()
        self.randomize = randomize
        self.privileged = privileged
        self.render_mode = render_mode
        if initial_cpg is not None:
            lo, hi = np.asarray(self.cpg_cfg.lower), np.asarray(self.cpg_cfg.upper)
            if np.any(np.asarray(initial_cpg) < lo) or np.any(np.asarray(initial_cpg) > hi):
                raise ValueError(f"initial_cpg={initial_cpg} is outside the CPG bounds {lo.tolist()}..{hi.tolist()}")
        self.initial_cpg = np.asarray(initial_cpg if initial_cpg is not None else self.cpg_cfg.initial, dtype=float)

        self.control_dt = 1.0 / self.sim_cfg.control_hz
        self.physics_dt = 1.0 / self.sim_cfg.physics_hz
        self.substeps = self.sim_cfg.physics_hz // self.sim_cfg.control_hz
        self.max_steps = math.ceil(self.task.time_limit / self.control_dt)
        self._stuck_steps = max(1, round(self.task.stuck_window / self.control_dt))

        self.client = p.connect(p.DIRECT)
        self._p = p
        self.gait = GaitMap(
            self.robot_spec, self.sim_cfg.body_height, self.sim_cfg.stance_reach, self.sim_cfg.lift_gain
        )
        self.cpg = CPG(self.cpg_cfg, np.array([leg.tripod for leg in self.robot_spec.legs]))
        self.trail = (LiftTrail(foot_lags(self.robot_spec, self.sim_cfg.stance_reach), self.max_steps + 1)
                      if self.cpg_cfg.lift_follows else None)
        on_map = partial(reflex_zone, self.sensor_cfg)
        self.reflex = (lift_reflex(on_map(self.task.lift_zone), RELIEF_M, self.cpg_cfg.lower[1], self.cpg_cfg.upper[1],
                                   self.cpg_cfg.rate_limit[1], self.cpg_cfg.falling_limit[1],
                                   self.task.lift_reflex_relief)
                       if self.task.reads_reflex else None)  # moves the legs only with task.lift_reflex
        short = self.task.stride_reflex or self.cpg_cfg.lower[0]  # the teacher alone asks for a's floor
        self.stride_reflex = (stride_reflex(on_map(self.task.lift_free_zone), short, self.cpg_cfg.upper[0],
                                            self.cpg_cfg.rate_limit[0], self.cpg_cfg.falling_limit[0])
                              if self.task.reads_stride else None)  # moves the legs only with task.stride_reflex
        self._readers: dict[str, Callable[[registry.SimView], np.ndarray]] = {}  # made on first use
        self.lift_cost_share = 1.0  # of task.lift_cost charged now: train-ppo's ppo.lift_cost_ramp lowers it

        self.action_space = spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
        self.observation_space = observation_space(self.cpg_cfg, self.sensor_cfg, self.task, privileged)
        self._observed = list(self.task.sensors)
        # what one observation reads: the observed sensors, and the height map for the privileged profile and the
        # reflexes (which read it whether or not the policy does)
        reflexes = self.reflex is not None or self.stride_reflex is not None
        needs_map = (privileged or reflexes) and "heightmap" not in self._observed
        self._sensed = self._observed + (["heightmap"] if needs_map else [])
        self._physics = (self.sim_cfg.friction, 1.0)  # (friction, base-mass scale) drawn at reset
        self._corridor = corridor_columns(self.sensor_cfg) if privileged else None
        order_one = self.cpg_cfg.action_order == 1
        self._action_scale = np.asarray(self.cpg_cfg.rate_limit if order_one else self.cpg_cfg.accel_limit)
        self._max_joint_step = self.robot_spec.speeds * self.physics_dt
        self.terrain: Terrain | None = None
        self.robot: Robot | None = None

    @classmethod
    def from_params(
        cls, params: Params, terrain: str | TerrainRecipe = "single_block", *,
        obs_sensors: Iterable[str] | None = None, **overrides: Any,
    ) -> HexapodEnv:
        """The env the params describe (sim, cpg, sensors, task). obs_sensors replaces `task.sensors` (the
        observed sensors; () for a bare env); overrides go to the constructor (initial_cpg, randomize, ...)."""
        return cls(terrain, sim=params.sim, cpg=params.cpg, sensors=params.sensors,
                   task=_observing(params.task, obs_sensors), **overrides)

    @staticmethod
    def observation_spec(params: Params, obs_sensors: Iterable[str] | None = None) -> spaces.Dict:
        """The observation space of `from_params(params, obs_sensors=...)`, without starting PyBullet."""
        return observation_space(params.cpg, params.sensors, _observing(params.task, obs_sensors))

    # -- episode -----------------------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        p, c = self._p, self.client
        p.resetSimulation(physicsClientId=c)
        p.setGravity(0, 0, -9.81, physicsClientId=c)
        p.setPhysicsEngineParameter(
            fixedTimeStep=self.physics_dt, numSolverIterations=self.sim_cfg.solver_iterations, physicsClientId=c
        )
        # options={"difficulty": d} (a curriculum's level, in [0, 1]) overrides a `varied` terrain's own difficulty
        self.terrain = realize(self.recipe, self.np_random, (options or {}).get("difficulty"))
        self.terrain_bodies = build_terrain(self.terrain, c)

        friction = self.terrain.friction or self.sim_cfg.friction
        mass_scale = 1.0
        if self.randomize:
            rnd = self.task.randomization
            friction = float(self.np_random.uniform(*rnd.friction))
            mass_scale = float(self.np_random.uniform(*rnd.mass_scale))

        phase0 = float(self.np_random.uniform(0.0, 2 * math.pi))
        self.cpg.reset(self.initial_cpg, phase0=phase0)
        if self.trail is not None:
            self.trail.reset()
        if self.reflex is not None:
            self.reflex.reset()
        if self.stride_reflex is not None:
            self.stride_reflex.reset()
        ground = float(self.terrain.height_at(np.zeros(1), np.zeros(1))[0])
        start = (0.0, 0.0, ground + self.sim_cfg.body_height + 0.01)
        self.robot = Robot(c, self.robot_spec, start)
        self.robot.set_friction(friction)
        for body in self.terrain_bodies:
            p.changeDynamics(body, -1, lateralFriction=friction, physicsClientId=c)
        if mass_scale != 1.0:
            self.robot.scale_base_mass(mass_scale)
        self._physics = (friction, mass_scale)
        self._xy = self.cpg.xy
        self._caught = np.zeros(len(self.robot_spec.legs), dtype=bool)  # legs the elevator reflex opens
        self._yaw = 0.0  # the base's yaw (rad) after the last control step: the heading reflex steers by it
        targets = self.gait.joint_targets(self._xy)
        self.robot.reset_joints(targets)
        self._targets = targets
        self.robot.command(targets, self.sim_cfg.position_gain, self.sim_cfg.velocity_gain)

        pos, _, _, _ = self.robot.base_state()
        self.start_xy = pos[:2].copy()
        self._last_x = float(pos[0])
        self._progress = deque([float(pos[0])], maxlen=self._stuck_steps + 1)
        self.steps = 0
        self.energy = 0.0  # J of mechanical joint work since reset
        self.last_info = self._info(pos, reward_terms={}, termination=None)
        return self._observation(), self.last_info

    def step(self, action: np.ndarray):
        assert self.robot is not None, "call reset() before step()"
        command = np.clip(np.asarray(action, dtype=float), -1.0, 1.0) * self._action_scale
        p, c = self._p, self.client
        gains = (self.sim_cfg.position_gain, self.sim_cfg.velocity_gain)
        # The CPG is open loop: plan the whole control step's joint targets at once, then run the physics
        floor = None
        if self.trail is not None:
            x = self._last_x
            self.trail.record(x, float(self.cpg.params[1]))
            floor = self.trail.floor(x)
        if self.reflex is not None:  # ramped over this control step from what the last height map showed
            lift = self.reflex.advance(self.control_dt)
            if self.task.lift_reflex:
                floor = np.full(len(self.robot_spec.legs), lift) if floor is None else np.maximum(floor, lift)
        cap = None
        if self.stride_reflex is not None:  # as the lift reflex: ramped from what the last height map showed
            stride = self.stride_reflex.advance(self.control_dt)
            cap = stride if self.task.stride_reflex > 0 else None
        xy = self.cpg.advance(command, self.physics_dt, self.substeps, floor, cap)
        elevator = self.sim_cfg.elevator_gain
        opening = elbow_opening(xy[..., 1], self._caught, elevator) if elevator > 0 else None
        steer = None
        if self.sim_cfg.heading_gain > 0:  # from the yaw the last control step ended with
            steer = stride_scales(self._yaw, self.gait.yaw_sign, self.sim_cfg.heading_gain)
        targets = slew_path(self._targets, self.gait.joint_targets(xy, opening, steer), self._max_joint_step)
        self._targets = targets[-1]
        self._xy = xy[-1]  # each leg's (x, y) now, with its lift floor (the recorder logs it)
        power = 0.0
        for target in targets:
            self.robot.command(target, *gains)
            p.stepSimulation(physicsClientId=c)
            power += self.robot.mechanical_power()
        power /= self.substeps
        self.steps += 1
        if elevator > 0:  # which legs the next control step opens: read once per step, after the physics
            pressed = pressed_from_side(contact_normals(c, self.robot.body, self.robot.foot_links))
            self._caught = caught_legs(self._caught, self._xy[:, 1], pressed)

        pos, quat, lin, _ = self.robot.base_state()
        if self.sim_cfg.heading_gain > 0:
            self._yaw = quat_to_yaw(quat)
        termination = None
        if not (np.all(np.isfinite(pos)) and np.all(np.isfinite(quat)) and np.all(np.isfinite(lin))):
            termination = "nonfinite"
            dx = 0.0
        else:
            dx = float(pos[0]) - self._last_x
            self._last_x = float(pos[0])
            self._progress.append(float(pos[0]))
            termination = self._termination(pos, quat)
        if not math.isfinite(power):
            power = 0.0
        self.energy += power * self.control_dt
        terms = self._reward_terms(dx, power, termination, self._lift_free(pos, quat))
        reward = sum(terms.values())
        truncated = termination is None and self.steps >= self.max_steps
        obs = self._observation() if termination != "nonfinite" else self._zero_observation()
        self.last_info = self._info(pos, terms, termination, power)
        return obs, reward, termination is not None, truncated, self.last_info

    def _reward_terms(
        self, dx: float, power: float, termination: str | None = None, lift_free: bool = False
    ) -> dict[str, float]:
        """The named reward terms of one control step: dx (m forward), power (W, mean mechanical joint power), how
        the step ended the episode, if it did, and whether the terrain around the body waives the lift price."""
        lift_cost = 0.0 if lift_free else self.task.lift_cost * self.lift_cost_share
        b = float(self.cpg.params[1])
        terms = {
            "forward": forward_velocity_reward(dx, self.control_dt, self.task.reward_scale),
            "power": power_penalty(power, self.task.power_cost),
            "lift": lift_penalty(b, self.cpg_cfg.lower[1], lift_cost),
            "failure": failure_penalty(termination, self.task.failure_penalty),
        }
        if self.task.lift_teacher > 0:  # only then, so that runs without it log the same terms as before
            terms["teacher"] = lift_shortfall_penalty(b, self.reflex.level, self.task.lift_teacher)
        if self.task.stride_teacher > 0:  # as the lift teacher
            terms["stride"] = stride_deviation_penalty(float(self.cpg.params[0]), self.stride_reflex.level,
                                                       self.task.stride_teacher)
        if self.task.time_cost > 0:  # as the teacher: runs without it log the terms they always did
            terms["time"] = time_penalty(self.control_dt, self.task.time_cost)
        return terms

    def _lift_free(self, pos: np.ndarray, quat: np.ndarray) -> bool:
        """Whether the price zone (task.lift_price_zone, else lift_free_zone) waives the lift price this step: the
        terrain from `behind` m behind the body to `ahead` m ahead of it rises or falls by more than a few cm (true
        terrain, seen by the reward only)."""
        zone = self.task.price_zone
        charged = self.task.lift_cost * self.lift_cost_share  # 0 during ppo.lift_cost_ramp's first part
        if zone is None or charged == 0.0 or not np.all(np.isfinite(pos)):
            return False
        return lift_waived(self.terrain.relief(float(pos[0]), float(pos[1]), quat_to_yaw(quat), *zone))

    def _termination(self, pos: np.ndarray, quat: np.ndarray) -> str | None:
        distance = float(pos[0] - self.start_xy[0])
        if distance >= self.task.goal_distance:
            return "goal"
        roll, pitch = quat_to_roll_pitch(quat)
        below = float(self.terrain.height_at(pos[:1], pos[1:2])[0])
        tilted = max(abs(roll), abs(pitch)) > self.task.fall_tilt
        if tilted or pos[2] - below < self.task.fall_height:
            return "fall"
        window_full = len(self._progress) > self._stuck_steps
        if window_full and self._progress[-1] - self._progress[0] < self.task.stuck_progress:
            return "stuck"
        return None

    # -- observation -------------------------------------------------------------------------------------------
    def _observation(self) -> dict[str, np.ndarray]:
        pos, quat, lin, ang = self.robot.base_state()
        below = float(self.terrain.height_at(pos[:1], pos[1:2])[0])
        body = np.concatenate([[pos[0] - self.start_xy[0], pos[1] - self.start_xy[1], pos[2] - below], quat, lin, ang])
        if not self.task.observe_position:
            body = body[2:]  # no x, y: height above the terrain, orientation and velocities only
        obs = {
            "body": np.clip(body, -100, 100).astype(np.float32),
            "cpg": np.concatenate([self.cpg.params, self.cpg.rates, self._phase()]).astype(np.float32),
        }
        sensed = self.sense(self._sensed, base=(pos, quat))
        if self.reflex is not None:
            self.reflex.see(sensed["heightmap"])
        if self.stride_reflex is not None:
            self.stride_reflex.see(sensed["heightmap"])
        for name in self._observed:
            obs[name] = registry.get(name).observation(sensed[name])
        if self.privileged:
            obs[PRIVILEGED] = privileged_vector(sensed["heightmap"], *self._physics, self.sensor_cfg, self._corridor)
        return obs

    def _phase(self) -> np.ndarray:
        """(cos, sin) of leg 0's oscillator phase with task.observe_phase, else empty: the tripods are locked to it,
        so it says where in its swing every leg is."""
        if not self.task.observe_phase:
            return np.empty(0)
        angle = float(np.angle(self.cpg.w[0]))
        return np.array([math.cos(angle), math.sin(angle)])

    def sense(self, names: Iterable[str], base: tuple[np.ndarray, np.ndarray] | None = None) -> dict[str, np.ndarray]:
        """Read the named sensors now (their readings, `Sensor.frame_shape`), e.g. `heightmap` (rows x cols, m
        above the stance plane), `rgb`, `contacts`.

        Independent of the observation's sensors, so a logger can record images on the steps it keeps only.
        """
        view = self.view(base)
        return {name: self.reader(name)(view) for name in names}

    def reader(self, name: str) -> Callable[[registry.SimView], np.ndarray]:
        """This env's reader of sensor `name` (made on first use: a camera only when something looks)."""
        reader = self._readers.get(name)
        if reader is None:
            reader = self._readers[name] = registry.get(name).reader(self.sensor_cfg)
        return reader

    def view(self, base: tuple[np.ndarray, np.ndarray] | None = None) -> registry.SimView:
        """What sensors read now; base: the base (position, quaternion) when already known."""
        pos, quat = base if base is not None else self.robot.base_state()[:2]
        return registry.SimView(self.client, self.robot, self.terrain, pos, quat, self.sim_cfg.body_height)

    def _zero_observation(self) -> dict[str, np.ndarray]:
        return {k: np.zeros(s.shape, dtype=s.dtype) for k, s in self.observation_space.spaces.items()}

    def _info(
        self, pos: np.ndarray, reward_terms: dict[str, float], termination: str | None, power: float = 0.0
    ) -> dict[str, Any]:
        distance = float(pos[0] - self.start_xy[0]) if np.all(np.isfinite(pos)) else 0.0
        return {
            "distance": distance,
            "success": termination == "goal",
            "termination": termination,
            "time": self.steps * self.control_dt,
            "cpg": self.cpg.params.copy(),
            "lift": self.lift,
            "stride": self.stride,
            "reward_terms": reward_terms,
            "power": power,  # W, mean mechanical joint power over the last control step
            "energy": self.energy,  # J since reset
        }

    # -- snapshots for the recorder ----------------------------------------------------------------------------
    def scene(self) -> EnvScene:
        """The realised terrain and the robot's geometry (fixed until the next reset)."""
        t = self.terrain
        return EnvScene(t.name, t.to_dict(), t.boxes, t.heightfields, robot_shapes(self.robot_spec))

    def state(self, sensors: Iterable[str] = ()) -> EnvState:
        """The env now, with the named sensors read: what the recorder logs for one step."""
        poses = self.robot.link_poses()
        base_pos, base_quat = poses[0]
        names = ["base_link", *self.robot_spec.link_names]
        transforms = [(WORLD_FRAME, name, pos, quat) for name, (pos, quat) in zip(names, poses, strict=True)]
        reference = self.sensor_cfg.heightmap_reference  # the height map's frame: its cells sit on the terrain
        plane = np.array([*base_pos[:2], reference_height(self.terrain, base_pos, self.sim_cfg.body_height, reference)])
        transforms.append((WORLD_FRAME, HEADING_FRAME, plane, _yaw_quaternion(quat_to_yaw(base_quat))))
        for sensor in registry.SENSORS.values():
            transforms.extend(sensor.frames(self.sensor_cfg))
        q, dq, tau = self.robot.joint_states()
        info = self.last_info
        return EnvState(
            step=self.steps, time=self.steps * self.control_dt, terrain=self.terrain.name,
            transforms=tuple(transforms), joint_names=tuple(self.robot_spec.joint_names),
            joint_position=q, joint_velocity=dq, joint_effort=tau,
            cpg_params=self.cpg.params.copy(), cpg_rates=self.cpg.rates.copy(), cpg_xy=self._xy.copy(),
            reward_terms=info["reward_terms"] or dict.fromkeys(self._reward_terms(0.0, 0.0), 0.0),
            power=float(info["power"]), energy=float(info["energy"]), distance=float(info["distance"]),
            termination=info["termination"], labels=self.terrain_labels(),
            readings=self.sense(sensors, base=(base_pos, base_quat)),
        )

    # -- extras for logging and video --------------------------------------------------------------------------
    def terrain_labels(self) -> dict[str, float]:
        """Labels for the VAE's probes, from one scan of the terrain ahead (`Terrain.rise_ahead`, 3 m): the
        `obstacle_distance` (m, inf if none within 3 m) and the next rise within the height map's far edge,
        `rise_distance` (m, inf if none) and `rise_height` (m, nan if none)."""
        pos, quat, _, _ = self.robot.base_state()
        distance, height = self.terrain.rise_ahead(float(pos[0]), float(pos[1]), quat_to_yaw(quat), max_range=3.0)
        in_reach = distance <= self.sensor_cfg.heightmap_ahead[1]
        return {
            "obstacle_distance": distance,
            "rise_distance": distance if in_reach else math.inf,
            "rise_height": height if in_reach else math.nan,
        }

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array" or self.robot is None:
            return None
        pos, _, _, _ = self.robot.base_state()
        p = self._p
        view = p.computeViewMatrixFromYawPitchRoll(pos.tolist(), 1.6, 50.0, -25.0, 0.0, 2)
        proj = p.computeProjectionMatrixFOV(60, 320 / 240, 0.05, 20.0)
        _, _, rgba, _, _ = p.getCameraImage(
            320, 240, view, proj, renderer=p.ER_TINY_RENDERER, flags=p.ER_NO_SEGMENTATION_MASK,
            physicsClientId=self.client,
        )
        return np.asarray(rgba, dtype=np.uint8).reshape(240, 320, 4)[:, :, :3]

    @property
    def lift(self) -> float:
        """The lift the front legs swing with now (rad): b, or the lift reflex's when that is higher (the middle
        and hind legs may swing higher still, following the leader with `cpg.lift_follows`)."""
        b = float(self.cpg.params[1])
        return max(b, self.reflex.level) if self.task.lift_reflex else b

    @property
    def stride(self) -> float:
        """The stride the legs swing with now (rad): a, or the stride reflex's when that is shorter."""
        a = float(self.cpg.params[0])
        return min(a, self.stride_reflex.level) if self.task.stride_reflex > 0 else a

    def set_lift_cost_share(self, share: float) -> None:
        """Charge `share` (in [0, 1]) of task.lift_cost from the next step: train-ppo ramps the price in with it."""
        self.lift_cost_share = float(share)

    def close(self) -> None:
        if getattr(self, "client", None) is not None:
            with suppress(Exception):  # already disconnected
                self._p.disconnect(physicsClientId=self.client)
            self.client = None


def _observing(task: TaskConfig, obs_sensors: Iterable[str] | None) -> TaskConfig:
    return task if obs_sensors is None else task.model_copy(update={"sensors": tuple(obs_sensors)})
