"""The sensor registry and the env built from it: observation specs without PyBullet, foot contacts read, observed
and logged, reward terms in /step and the training curves."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from hexpipe.config import Params, TaskConfig
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.recording.episode import EpisodeLog
from hexpipe.recording.reader import count_messages, iter_frames
from hexpipe.rl.callbacks import EpisodeStats
from hexpipe.sensors import SENSORS, get, image_sensors, names

WEIGHT_N = 20.2 * 9.81  # the robot's weight (RobotSpec.total_mass about 20.2 kg)


def test_registry_names_and_errors() -> None:
    assert names() == ("rgb", "heightmap", "contacts") and image_sensors() == ("rgb", "heightmap")
    with pytest.raises(ValueError, match="unknown sensor 'depth'; known: rgb, heightmap, contacts"):
        get("depth")
    with pytest.raises(ValueError, match="not an image sensor"):
        Params.model_validate({"vae": {"modality": "contacts"}})


@pytest.mark.parametrize("sensors", [(), ("heightmap",), ("rgb", "heightmap", "contacts"), ("contacts",)])
def test_observation_spec_matches_a_live_env(sensors: tuple[str, ...]) -> None:
    params = Params()
    spec = HexapodEnv.observation_spec(params, obs_sensors=sensors)
    env = HexapodEnv.from_params(params, "flat", obs_sensors=sensors)
    try:
        assert spec == env.observation_space
        obs, _ = env.reset(seed=0)
        assert spec.contains(obs) and set(obs) == {"body", "cpg", *sensors}
        for name in sensors:  # the reading, as the observation holds it
            reading = env.sense((name,))[name]
            assert reading.shape == SENSORS[name].frame_shape(params.sensors)
    finally:
        env.close()


def test_foot_contacts_carry_the_weight_and_do_not_change_the_rollout() -> None:
    observed = HexapodEnv("flat", task=TaskConfig(sensors=("contacts",)))
    blind = HexapodEnv("flat", task=TaskConfig(sensors=()))
    try:
        obs_c, _ = observed.reset(seed=3)
        obs_b, _ = blind.reset(seed=3)
        forces, stance = [], []
        for _ in range(40):
            obs_c, *_ = observed.step(np.zeros(3))
            obs_b, *_ = blind.step(np.zeros(3))
            assert np.array_equal(obs_c["body"], obs_b["body"])  # reading contacts leaves the physics alone
            contact, force = obs_c["contacts"][:6], obs_c["contacts"][6:]
            assert set(np.unique(contact)) <= {0.0, 1.0} and np.all(force[contact == 0] == 0)
            forces.append(force.sum())
            stance.append(contact.sum())
        # walking on flat ground, the feet on the ground carry the robot: about its weight on average, and a tripod
        # or more stands at most steps
        assert 0.7 * WEIGHT_N < np.mean(forces[10:]) < 1.3 * WEIGHT_N
        assert np.median(stance) >= 3 and min(stance) >= 1
    finally:
        observed.close()
        blind.close()


def test_contacts_and_reward_terms_are_logged(tmp_path: Path) -> None:
    env = HexapodEnv("flat", task=TaskConfig(sensors=(), power_cost=0.01))
    try:
        env.reset(seed=0)
        with EpisodeLog(env, tmp_path / "ep.mcap", {}) as log:
            log.step(0.0, force=True)
            for _ in range(4):
                _, reward, _, _, info = env.step(np.zeros(3))
                log.step(reward, force=True)
        last = env.sense(("contacts",))["contacts"]
    finally:
        env.close()
    counts = count_messages(tmp_path / "ep.mcap")
    assert counts["/contacts"] == counts["/step"] == 5 and counts["/heightmap"] == 5
    frames = list(iter_frames(tmp_path / "ep.mcap", ("contacts",)))
    assert np.array_equal(frames[-1].sensors["contacts"], last)
    # after reset: every term, at 0 (the lift teacher is on by default, so its term is logged too)
    assert frames[0].meta["reward_terms"] == {"forward": 0.0, "power": 0.0, "lift": 0.0, "failure": 0.0, "teacher": 0.0}
    terms = frames[-1].meta["reward_terms"]
    assert terms == pytest.approx(info["reward_terms"]) and terms["power"] < 0
    assert sum(terms.values()) == pytest.approx(frames[-1].meta["reward"])


def test_episode_stats_log_a_curve_per_reward_term() -> None:
    stats = EpisodeStats()
    venv = SimpleNamespace(num_envs=2)
    stats.model = SimpleNamespace(get_vec_normalize_env=lambda: None, get_env=lambda: venv)
    stats.num_timesteps = 0
    stats._on_training_start()
    for done in (False, False, True):
        stats.num_timesteps += 2
        infos = [{"reward_terms": {"forward": 2.0, "power": -0.5}}, {"reward_terms": {"forward": 1.0, "power": 0.0}}]
        stats.locals = {"rewards": np.array([1.5, 1.0]), "dones": [done, done], "infos": infos}
        stats._on_step()
    recent = stats.recent()
    assert recent["episode/reward"] == pytest.approx(3.75)
    assert recent["episode/reward_forward"] == pytest.approx(4.5) and recent["episode/reward_power"] == pytest.approx(
        -0.75)
    assert stats.episodes[0]["reward_terms"] == {"forward": 6.0, "power": -1.5}
