"""Best of K (ppo.candidates): every candidate is an ordinary run of its seed, the one with the highest validation
return is exported, one candidate is the single run it always was, and outputs depend on the params alone."""

import json
from pathlib import Path

import pytest

import hexpipe.rl.selection as selection
from hexpipe.config import ConfigError, Params, load_params
from hexpipe.rl.selection import (
    SELECTION,
    VALIDATION,
    candidate_params,
    candidate_seeds,
    choose,
    train_policy,
    validation_episodes,
)
from hexpipe.sim.terrain import TerrainError

ROOT = Path(__file__).resolve().parents[1]
TINY = ["ppo.total_timesteps=128", "ppo.n_envs=1", "ppo.n_steps=64", "ppo.batch_size=64", "ppo.n_epochs=1",
        "ppo.blind=true", "ppo.train_terrains=[single_block]", "task.time_limit=1.0", "ppo.validation_episodes=3",
        "ppo.candidates=1"]


def tiny(root: Path, *extra: str) -> Params:
    return load_params(ROOT / "params.yaml", [*TINY, f"ppo.out_dir={root / 'ppo'}",
                                              f"ppo.report_dir={root / 'reports'}", *extra])


def no_episode(_args):
    """Stands in for a validation episode where none may run (module level: the worker pool pickles it by name)."""
    raise AssertionError("a validation episode ran again")


def test_candidate_seeds_step_by_a_thousand_and_choice_keeps_the_first_of_equal_returns():
    assert candidate_seeds(7, 3) == [7, 1007, 2007]
    assert candidate_seeds(0, 1) == [0]
    assert choose([1.0, 3.0, 3.0]) == 1 and choose([-5.0]) == 0
    with pytest.raises(ValueError, match="no candidates"):
        choose([])


def test_success_first_lets_only_the_candidates_near_the_best_success_compete_on_return():
    returns, successes = [1400.0, 1200.0, 900.0], [0.85, 0.95, 0.9333]
    assert choose(returns) == 0  # the return rule keeps the draw that fails most
    assert choose(returns, successes, tolerance=0.04) == 1
    assert choose(returns, successes, tolerance=0.0) == 1
    assert choose(returns, successes, tolerance=0.1) == 0  # 0.85 is within 0.1 of 0.95: return decides again
    assert choose([900.0, 1000.0], [0.9, 0.9], tolerance=0.0) == 1  # equal success: the return breaks the tie
    with pytest.raises(ValueError, match="2 success rates for 3 candidates"):
        choose(returns, [0.9, 0.9])


def test_one_candidate_keeps_its_folders_and_several_get_their_own(tmp_path):
    one = tiny(tmp_path)
    assert candidate_params(one, 0) is one
    three = tiny(tmp_path, "ppo.candidates=3")
    run = candidate_params(three, 1000).ppo
    assert run.seed == 1000
    assert Path(run.out_dir) == tmp_path / "ppo" / "candidates" / "seed1000"
    assert Path(run.report_dir) == tmp_path / "reports" / "candidates" / "seed1000"


def test_validation_episodes_take_the_training_terrains_in_turn_from_seed_5000(tmp_path):
    params = tiny(tmp_path, "ppo.train_terrains=[flat, single_block]", "ppo.n_envs=2", "ppo.validation_episodes=3")
    assert validation_episodes(params) == [("flat", 5000), ("single_block", 5001), ("flat", 5002)]


def test_several_candidates_need_validation_episodes():
    with pytest.raises(ConfigError, match="validation_episodes"):
        load_params(ROOT / "params.yaml", ["ppo.candidates=2", "ppo.validation_episodes=0"])


def test_best_of_two_exports_the_higher_validation_return_and_each_candidate_is_its_seeds_single_run(
        tmp_path, monkeypatch):
    params = tiny(tmp_path / "pick", "ppo.candidates=2", "ppo.seed=3")
    metrics = train_policy(params, show_progress=False)
    out, reports = tmp_path / "pick" / "ppo", tmp_path / "pick" / "reports"
    chosen = json.loads((reports / SELECTION).read_text())
    returns = {int(seed): s["return"] for seed, s in chosen["candidates"].items()}
    assert sorted(returns) == [3, 1003]
    best = max(returns, key=returns.get)
    assert chosen["chosen_seed"] == best == metrics["selection/chosen_seed"]
    assert metrics["selection/validation_return"] == returns[best]
    assert chosen["candidates"][str(best)]["episodes"] == 3

    # the exported policy and the training reports are the chosen candidate's, byte for byte
    pick = out / "candidates" / f"seed{best}"
    assert (out / "policy" / "weights.pt").read_bytes() == (pick / "policy" / "weights.pt").read_bytes()
    assert (out / "policy.json").read_text() == (pick / "policy.json").read_text()
    picked_reports = reports / "candidates" / f"seed{best}"
    assert (reports / "metrics.json").read_text() == (picked_reports / "metrics.json").read_text()
    assert not (out / "checkpoints").exists()

    # candidate 1003 is what a single run of seed 1003 trains: selection only chooses
    single = tiny(tmp_path / "single", "ppo.seed=1003")
    alone = train_policy(single, show_progress=False)
    assert alone["selection/chosen_seed"] == 1003 and not alone["finished"]
    assert ((tmp_path / "single" / "ppo" / "policy" / "weights.pt").read_bytes()
            == (out / "candidates" / "seed1003" / "policy" / "weights.pt").read_bytes())
    assert not (tmp_path / "single" / "ppo" / "candidates").exists()
    single_scores = json.loads((tmp_path / "single" / "reports" / SELECTION).read_text())["candidates"]["1003"]
    assert single_scores == chosen["candidates"]["1003"]  # the validation is deterministic

    # resuming a finished selection trains nothing and reuses the saved scores (no episode runs)
    monkeypatch.setattr(selection, "_validation_episode", no_episode)
    again = train_policy(params, resume=True, show_progress=False)
    assert again["finished"] and again["selection/chosen_seed"] == best
    assert json.loads((out / "candidates" / f"seed{best}" / VALIDATION).read_text())["scores"]["return"] == \
        returns[best]

    # other weights under the same signature (retrained on another CPU, or pulled): scored again, not read back
    weights = out / "candidates" / "seed3" / "policy" / "weights.pt"
    weights.write_bytes(weights.read_bytes() + b"\0")
    with pytest.raises(AssertionError, match="ran again"):
        train_policy(params, resume=True, show_progress=False)


def test_fewer_candidates_drop_the_folders_of_more(tmp_path):
    train_policy(tiny(tmp_path, "ppo.candidates=2"), show_progress=False)
    assert (tmp_path / "ppo" / "candidates" / "seed1000").is_dir()
    train_policy(tiny(tmp_path, "ppo.validation_episodes=0"), show_progress=False)
    assert not (tmp_path / "ppo" / "candidates").exists() and not (tmp_path / "reports" / "candidates").exists()
    assert (tmp_path / "ppo" / "checkpoints").is_dir()
    record = json.loads((tmp_path / "reports" / SELECTION).read_text())
    assert record["chosen_seed"] == 0 and record["candidates"] == {}  # no validation asked for: nothing scored


def test_success_first_keeps_the_candidate_that_crosses_more_though_its_return_is_lower(tmp_path, monkeypatch):
    canned = {3: {"return": 1400.0, "success": 0.85}, 1003: {"return": 1200.0, "success": 0.95}}

    def scores(run, _out, _signature, workers):
        return {**canned[run.ppo.seed], "distance": 3.0, "b_mean": 0.3, "episodes": 3}

    monkeypatch.setattr(selection, "validate", scores)
    kept = {}
    for rule in ("return", "success"):
        params = tiny(tmp_path / rule, "ppo.candidates=2", "ppo.seed=3", f"ppo.selection={rule}")
        kept[rule] = train_policy(params, show_progress=False)["selection/chosen_seed"]
        record = json.loads((tmp_path / rule / "reports" / SELECTION).read_text())
        assert record["chosen_seed"] == kept[rule]
    assert kept == {"return": 3, "success": 1003}
    with pytest.raises(ConfigError, match="selection"):
        load_params(ROOT / "params.yaml", ["ppo.selection=best"])


def test_validation_terrains_rescore_the_trained_policy_and_an_edited_terrain_file_is_scored_anew(
        tmp_path, monkeypatch):
    train_policy(tiny(tmp_path), show_progress=False)  # validated on its training terrain, single_block
    weights = (tmp_path / "ppo" / "policy" / "weights.pt").read_bytes()
    course = tmp_path / "course.yaml"
    course.write_text("boxes:\n  - {face: 0.8, depth: 0.3, height: 0.1}\n")
    params = tiny(tmp_path, f"ppo.validation_terrains=[flat, {course}]")
    assert validation_episodes(params) == [("flat", 5000), (str(course), 5001), ("flat", 5002)]

    monkeypatch.setattr(selection, "_validation_episode", no_episode)
    with pytest.raises(AssertionError, match="ran again"):  # other terrains: the saved scores are not reused
        train_policy(params, resume=True, show_progress=False)
    monkeypatch.undo()
    again = train_policy(params, resume=True, show_progress=False)
    assert again["finished"]  # a selection-only key: the policy is not retrained
    assert (tmp_path / "ppo" / "policy" / "weights.pt").read_bytes() == weights
    record = json.loads((tmp_path / "reports" / SELECTION).read_text())
    assert record["validation"]["terrains"] == ["flat", str(course)]
    rows = json.loads((tmp_path / "ppo" / VALIDATION).read_text())["rows"]
    assert [r["terrain"] for r in rows] == ["flat", str(course), "flat"]

    monkeypatch.setattr(selection, "_validation_episode", no_episode)
    train_policy(params, resume=True, show_progress=False)  # the same terrains: read back, no episode runs
    course.write_text("boxes:\n  - {face: 0.8, depth: 0.3, height: 0.05}\n")
    with pytest.raises(AssertionError, match="ran again"):  # the same path, another course
        train_policy(params, resume=True, show_progress=False)


def test_bad_validation_terrains_are_named_before_any_training(tmp_path):
    with pytest.raises(ConfigError, match="validation_terrains is empty"):
        tiny(tmp_path, "ppo.validation_terrains=[]")
    with pytest.raises(TerrainError, match=r"ppo\.validation_terrains: unknown terrain 'nowhere_land'"):
        train_policy(tiny(tmp_path, "ppo.validation_terrains=[nowhere_land]"), show_progress=False)
    assert not (tmp_path / "ppo").exists()
