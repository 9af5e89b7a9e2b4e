"""`hexpipe/Hexapod-v0`: the paper's POMDP. The policy sets the second derivative of the CPG parameters.

Observation (Dict):
- `body` (13): position relative to the start (x, y; z = base height above the terrain below), orientation
  quaternion (xyzw), linear velocity (m/s) and angular velocity (rad/s), world frame; 11 without x, y when
  `TaskConfig.observe_position` is false (the same course shifted along x then looks the same at the same
  distance from its block);
- `cpg` (6): a, b, omega and their rates;
- `heightmap` (rows * cols,) float32 m, row-major (reshape with `env.heightmap.shape`; flat because SB3 expects
  1-D vectors or images), and/or `rgb` (H, W, 3) uint8, as selected by `TaskConfig.sensors`.
Action: Box [-1, 1]^3, scaled by `CpgConfig.accel_limit` to d^2/dt^2 (a, b, omega).
Reward: `reward_scale` * forward velocity (m/s, displacement over the control step), as in the paper, minus
`power_cost` * mean mechanical joint power (W) when that is set (0 is the paper's reward).
Terminates on `goal` (3 m forward), `stuck` (too little progress over a window), `fall` (tilt or base too low)
or `nonfinite` physics; truncates at the time limit. `info` carries distance, success, termination and the
reward terms.
"""

from __future__ import annotations

import math
from collections import deque
from contextlib import suppress
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from hexpipe.config import CpgConfig, SensorConfig, SimConfig, TaskConfig
from hexpipe.envs.rewards import forward_velocity_reward, power_penalty
from hexpipe.sim.cpg import CPG
from hexpipe.sim.gait import GaitMap, slew_path
from hexpipe.sim.robot import Robot, RobotSpec
from hexpipe.sim.sensors import Camera, HeightMapSensor
from hexpipe.sim.terrain import Terrain, TerrainRecipe, build_terrain, load_terrain, realize


def quat_to_roll_pitch(q: np.ndarray) -> tuple[float, float]:
    x, y, z, w = q
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    return roll, pitch


def quat_to_yaw(q: np.ndarray) -> float:
    x, y, z, w = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


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
    ):
        import pybullet as p

        self.sim_cfg = sim or SimConfig()
        self.cpg_cfg = cpg or CpgConfig()
        self.sensor_cfg = sensors or SensorConfig()
        self.task = task or TaskConfig()
        self.recipe = load_terrain(terrain) if isinstance(terrain, str) else terrain
        self.robot_spec = robot or RobotSpec()
        self.randomize = randomize
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
        self.heightmap = HeightMapSensor(self.sensor_cfg)
        self.camera: Camera | None = None  # made on first use: only rgb observations or loggers need it

        self.action_space = spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
        self.observation_space = spaces.Dict(self._observation_spaces())
        self._accel_limit = np.asarray(self.cpg_cfg.accel_limit)
        self._max_joint_step = self.robot_spec.speeds * self.physics_dt
        self.terrain: Terrain | None = None
        self.robot: Robot | None = None

    def _observation_spaces(self) -> dict[str, spaces.Space]:
        lo, hi = np.asarray(self.cpg_cfg.lower), np.asarray(self.cpg_cfg.upper)
        rate = np.asarray(self.cpg_cfg.rate_limit)
        obs: dict[str, spaces.Space] = {
            "body": spaces.Box(-100.0, 100.0, shape=(13 if self.task.observe_position else 11,), dtype=np.float32),
            "cpg": spaces.Box(
                np.concatenate([lo, -rate]).astype(np.float32), np.concatenate([hi, rate]).astype(np.float32)
            ),
        }
        if "heightmap" in self.task.sensors:
            obs["heightmap"] = spaces.Box(-5.0, 5.0, shape=(self.heightmap.size,), dtype=np.float32)
        if "rgb" in self.task.sensors:
            shape = (self.sensor_cfg.camera_height, self.sensor_cfg.camera_width, 3)
            obs["rgb"] = spaces.Box(0, 255, shape=shape, dtype=np.uint8)
        return obs

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
        ground = float(self.terrain.height_at(np.zeros(1), np.zeros(1))[0])
        start = (0.0, 0.0, ground + self.sim_cfg.body_height + 0.01)
        self.robot = Robot(c, self.robot_spec, start)
        self.robot.set_friction(friction)
        for body in self.terrain_bodies:
            p.changeDynamics(body, -1, lateralFriction=friction, physicsClientId=c)
        if mass_scale != 1.0:
            self.robot.scale_base_mass(mass_scale)
        targets = self.gait.joint_targets(self.cpg.xy)
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
        accel = np.clip(np.asarray(action, dtype=float), -1.0, 1.0) * self._accel_limit
        p, c = self._p, self.client
        gains = (self.sim_cfg.position_gain, self.sim_cfg.velocity_gain)
        # The CPG is open loop: plan the whole control step's joint targets at once, then run the physics
        xy = self.cpg.advance(accel, self.physics_dt, self.substeps)
        targets = slew_path(self._targets, self.gait.joint_targets(xy), self._max_joint_step)
        self._targets = targets[-1]
        power = 0.0
        for target in targets:
            self.robot.command(target, *gains)
            p.stepSimulation(physicsClientId=c)
            power += self.robot.mechanical_power()
        power /= self.substeps
        self.steps += 1

        pos, quat, lin, _ = self.robot.base_state()
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
        terms = {
            "forward": forward_velocity_reward(dx, self.control_dt, self.task.reward_scale),
            "power": power_penalty(power, self.task.power_cost),
        }
        reward = sum(terms.values())
        truncated = termination is None and self.steps >= self.max_steps
        obs = self._observation() if termination != "nonfinite" else self._zero_observation()
        self.last_info = self._info(pos, terms, termination, power)
        return obs, reward, termination is not None, truncated, self.last_info

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
            "cpg": np.concatenate([self.cpg.params, self.cpg.rates]).astype(np.float32),
        }
        sensed = self.sense(self.task.sensors, base=(pos, quat))
        if "heightmap" in sensed:
            obs["heightmap"] = sensed["heightmap"].reshape(-1)
        if "rgb" in sensed:
            obs["rgb"] = sensed["rgb"]
        return obs

    def sense(self, modalities, base=None) -> dict[str, np.ndarray]:
        """Read terrain sensors now: `heightmap` (rows x cols, m above the stance plane) and/or `rgb`.

        Independent of the observation's sensors, so a logger can record images on the steps it keeps only.
        """
        pos, quat = base if base is not None else self.robot.base_state()[:2]
        out: dict[str, np.ndarray] = {}
        if "heightmap" in modalities:
            plane = pos[2] - self.sim_cfg.body_height
            grid = self.heightmap.read(self.terrain, pos[:2], quat_to_yaw(quat), plane)
            out["heightmap"] = np.clip(grid, -5.0, 5.0)
        if "rgb" in modalities:
            if self.camera is None:
                self.camera = Camera(self.sensor_cfg, self.client)
            out["rgb"] = self.camera.read(pos, quat)
        return out

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
            "reward_terms": reward_terms,
            "power": power,  # W, mean mechanical joint power over the last control step
            "energy": self.energy,  # J since reset
        }

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

    def close(self) -> None:
        if getattr(self, "client", None) is not None:
            with suppress(Exception):  # already disconnected
                self._p.disconnect(physicsClientId=self.client)
            self.client = None
