"""The terrain curriculum: legged_gym's rule on synthetic distances, the env wrapper, and its training curve."""

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.rl.curriculum import Curriculum, next_level

GOAL = 3.0


def test_rule_promotes_demotes_and_stays_on_synthetic_distances() -> None:
    rng = np.random.default_rng(0)
    assert next_level(4, 3.0, GOAL, 10, rng) == 5  # walked the whole course
    assert next_level(4, 3.2, GOAL, 10, rng) == 5
    assert next_level(4, 1.49, GOAL, 10, rng) == 3  # less than half of it
    assert next_level(0, 0.2, GOAL, 10, rng) == 0  # no level below 0
    assert next_level(4, 1.5, GOAL, 10, rng) == 4  # half or more, but not all: stay
    assert next_level(4, 2.9, GOAL, 10, rng) == 4
    # the top level, completed: a random level, seeded
    tops = [next_level(9, 3.0, GOAL, 10, np.random.default_rng(seed)) for seed in range(40)]
    assert tops == [next_level(9, 3.0, GOAL, 10, np.random.default_rng(seed)) for seed in range(40)]
    assert min(tops) >= 0 and max(tops) <= 9 and len(set(tops)) > 3


class Scripted(gym.Env):
    """Episodes of one step that walk the next scripted distance; records the difficulty each reset asked for."""

    observation_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
    action_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)

    def __init__(self, distances: list[float]):
        self.distances, self.asked = list(distances), []

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.asked.append(options["difficulty"])
        return np.zeros(1, np.float32), {}

    def step(self, action):
        return np.zeros(1, np.float32), 0.0, True, False, {"distance": self.distances.pop(0)}


def test_wrapper_moves_the_level_between_episodes_and_reports_it() -> None:
    env = Scripted([3.0, 3.0, 2.0, 0.5, 0.5, 0.5, 3.0])
    wrapped = Curriculum(env, goal=GOAL, n_levels=5)
    _, info = wrapped.reset(seed=0)
    levels = [info["difficulty"]]
    for _ in range(7):
        _, _, _, _, info = wrapped.step(np.zeros(1))
        assert info["difficulty"] == levels[-1]  # the level of the episode that just ended
        _, info = wrapped.reset()
        levels.append(info["difficulty"])
    assert [round(4 * d) for d in levels] == [0, 1, 2, 2, 1, 0, 0, 1]
    assert env.asked == levels  # passed to the env as reset(options={"difficulty"})
    with pytest.raises(ValueError, match="n_levels"):
        Curriculum(env, goal=GOAL, n_levels=1)


def test_level_reaches_the_varied_terrain() -> None:
    env = Curriculum(HexapodEnv("varied"), goal=GOAL, level=0)
    heights = set()
    for seed in range(8):
        env.reset(seed=seed)
        heights |= {b.size[2] for b in env.unwrapped.terrain.boxes}
    assert heights == {0.04}  # level 0: only the lowest blocks
    env.close()


def test_training_with_the_curriculum_logs_its_curve(tmp_path: Path) -> None:
    from hexpipe.config import load_params
    from hexpipe.rl.train import train_ppo

    root = Path(__file__).resolve().parents[1]
    params = load_params(root / "params.yaml", [
        "ppo.total_timesteps=128", "ppo.n_steps=64", "ppo.batch_size=64", "ppo.n_epochs=1", "ppo.n_envs=1",
        "ppo.blind=true", "ppo.train_terrains=[varied]", "ppo.curriculum=true", "task.time_limit=1.0",
        f"ppo.out_dir={tmp_path / 'ppo'}", f"ppo.report_dir={tmp_path / 'reports'}",
    ])
    train_ppo(params, show_progress=False)
    curve = (tmp_path / "reports" / "plots" / "metrics" / "curriculum" / "difficulty.tsv").read_text().splitlines()
    assert curve[0].split("\t") == ["step", "difficulty"] and len(curve) == 3  # one row per rollout
    assert all(float(row.split("\t")[1]) == 0.0 for row in curve[1:])  # 1 s episodes never complete the course
