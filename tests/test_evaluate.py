"""The evaluate stage: a tiny real policy through the whole suite, and one-line errors before any episode runs."""

import json
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from stable_baselines3.common.vec_env import DummyVecEnv

from hexpipe.config import ConfigError, Params, load_params
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.evaluation.controllers import ControllerSpec, grid_gaits
from hexpipe.evaluation.episodes import TRACE_COLUMNS, EpisodeJob, legs_at_faces, lift_before_and_away, run_episode
from hexpipe.evaluation.metrics import rank_gaits, stall_counts
from hexpipe.evaluation.run import GRID_SEEDS, evaluate
from hexpipe.evaluation.suite import load_scenarios
from hexpipe.evaluation.video import count_frames
from hexpipe.models.vae import ConvVAE, encoder_config, export_encoder
from hexpipe.recording.reader import count_messages, read_metadata
from hexpipe.rl.features import TerrainEmbedding, TerrainFeatures
from hexpipe.rl.policy import PolicyError, load_policy
from hexpipe.rl.train import train_ppo
from hexpipe.sim.terrain import TerrainError

ROOT = Path(__file__).resolve().parents[1]
TINY_PPO = ["ppo.total_timesteps=256", "ppo.n_envs=1", "ppo.train_terrains=[single_block]", "ppo.n_steps=128",
            "ppo.batch_size=64", "ppo.n_epochs=1", "task.time_limit=2.0"]


def trained(root: Path, *extra: str) -> Params:
    """Params whose ppo.out_dir holds a freshly trained tiny policy (and eval.policy_dir points at it)."""
    params = load_params(ROOT / "params.yaml", [
        *TINY_PPO, f"ppo.out_dir={root / 'ppo'}", f"ppo.report_dir={root / 'ppo-report'}",
        f"eval.policy_dir={root / 'ppo'}", f"eval.out_dir={root / 'eval'}", f"eval.report_dir={root / 'report'}",
        "eval.terrains=[single_block, extra_blocks]", "eval.episodes=2", "eval.grid_a=[0.3]", "eval.grid_b=[0.3]",
        "eval.grid_omega=[4.712389]", *extra,
    ])
    train_ppo(params, show_progress=False)
    return params


@pytest.fixture(scope="module")
def blind(tmp_path_factory) -> Params:
    return trained(tmp_path_factory.mktemp("blind"), "ppo.blind=true")


@pytest.fixture(scope="module")
def seeing(tmp_path_factory) -> Params:
    """A tiny policy that sees the height map through an (untrained) 32x32 VAE encoder with 8 latents."""
    root = tmp_path_factory.mktemp("seeing")
    model = ConvVAE(in_channels=1, image_size=64, latent_dim=8)
    export_encoder(model, root / "vae", encoder_config(model, "heightmap", (32, 32)))
    return trained(root, f"ppo.encoder_dir={root / 'vae'}")


def test_evaluate_writes_metrics_report_recordings_and_video(blind):
    params = blind.model_copy(update={"eval": blind.eval.model_copy(update={"blind_policy_dir": blind.ppo.out_dir})})
    summary = evaluate(params, show_progress=False)
    out, report = Path(blind.eval.out_dir), Path(blind.eval.report_dir)
    assert "single_block" in summary and "report.md" in summary

    metrics = json.loads((report / "metrics.json").read_text())
    terrains = {k: v for k, v in metrics.items() if isinstance(v, dict)}
    assert list(terrains) == ["single_block", "extra_blocks"]
    for row in terrains.values():
        assert list(row) == ["policy", "blind", "best_fixed", "reflex_gait", "open_loop"]  # default: reflex gait on
        for m in row.values():
            assert m["episodes"] == 2
            for key in ("success_rate", "fall_rate", "stuck_rate"):
                assert 0.0 <= m[key] <= 1.0
            assert m["success_ci_low"] <= m["success_rate"] <= m["success_ci_high"]
            assert m["distance_std"] >= 0 and all(isinstance(v, int | float) for v in m.values())
    fixed = metrics["single_block"]["best_fixed"]
    assert (fixed["a_mean"], fixed["b_mean"]) == pytest.approx((0.3, 0.3))  # the 1-point grid's gait, held
    for name in ("policy", "blind"):  # the verdict, flat numbers beside the terrains
        assert metrics[f"verdict/{name}/terrains"] == 2
        assert metrics[f"verdict/{name}/beats_best_fixed_everywhere"] in (0, 1)

    rows = pd.read_csv(report / "results.csv")
    grid_rows = len(blind.ppo.train_terrains) * GRID_SEEDS  # the 1-gait grid, on every training terrain
    assert len(rows) == 2 * 5 * 2 + grid_rows  # terrains x controllers x episodes, plus the grid
    assert set(rows.loc[rows["controller"] == "grid", "terrain"]) == set(blind.ppo.train_terrains)
    evaluated = rows[rows["controller"] != "grid"]
    assert set(evaluated.groupby("controller")["seed"].apply(tuple)) == {(1000, 1001, 1000, 1001)}  # same seeds
    assert set(rows.loc[rows["controller"] == "grid", "seed"]).isdisjoint({1000, 1001})

    assert evaluated["stall_legs"].isna().all()  # a 2 s limit: nothing ends stuck or fallen

    text = (report / "report.md").read_text()
    assert "## Where the failed episodes stopped\n\nFor every" in text and "Every episode reached the goal" in text
    assert "ppo-blind from" in text and "hexpipe evaluate" in text and "a=0.30 b=0.30 omega=1.50pi" in text
    assert "fails on a wider block" not in text  # claims only for the terrains evaluated
    assert "crosses the block it was trained on" in text
    assert "## Verdict" in text and "### `policy`" in text and "### `blind`" in text
    for name in ("success.png", "cpg_single_block.png", "cpg_extra_blocks.png", "grid.csv", "gait_single_block.png",
                 "gait_extra_blocks.png"):
        assert (report / name).stat().st_size > 0
    assert "![gait diagram on single_block](gait_single_block.png)" in text

    for terrain in ("single_block", "extra_blocks"):
        files = sorted((out / terrain).glob("*.mcap"))
        assert [f.name for f in files] == ["ep_0.mcap", "ep_1.mcap"]
        counts = count_messages(files[0])
        assert counts["/step"] >= 2 and counts["/terrain"] == 1
        assert counts["/contacts"] == counts["/step"]  # always logged, whatever the policy observes
        meta = read_metadata(files[1])["episode"]
        assert (meta["seed"], meta["controller"], meta["terrain"]) == ("1001", "policy", terrain)
        first = rows[(rows["terrain"] == terrain) & (rows["controller"] == "policy") & (rows["episode"] == 0)]
        assert count_frames(out / f"{terrain}.mp4") == 1 + first["steps"].item()  # reset + every step
    assert not list(out.rglob("*.tmp*")) and not list(report.rglob("*.tmp*"))


def test_evaluate_with_a_reflex_gait_also_judges_the_policy_against_it(seeing, tmp_path):
    """eval.reflex_gait adds the hand-made adaptive baseline: its rows, its metrics and a second verdict."""
    cfg = seeing.eval.model_copy(update={
        "reflex_gait": (0.3, 0.2, 4.712389), "terrains": ("single_block",), "episodes": 1, "record_video": False,
        "log_episodes": 0, "out_dir": str(tmp_path / "eval"), "report_dir": str(tmp_path / "report")})
    evaluate(seeing.model_copy(update={"eval": cfg}), show_progress=False)
    metrics = json.loads((tmp_path / "report" / "metrics.json").read_text())
    assert list(metrics["single_block"]) == ["policy", "best_fixed", "reflex_gait", "open_loop"]
    assert metrics["verdict_vs_reflex_gait/policy/terrains"] == 1
    assert metrics["verdict_vs_reflex_gait/policy/terrains_beaten"] in (0, 1)
    text = (tmp_path / "report" / "report.md").read_text()
    assert "Against `reflex_gait`" in text and "a=0.30 b=0.20 omega=1.50pi with the lift reflex moving" in text


def test_the_reflex_gait_crosses_the_block_its_fixed_gait_stalls_at():
    """The physical premise of `reflex_gait`: a gait at b's floor stalls at the block; the same gait with the lift
    reflex moving its legs crosses it, and the params' own task.lift_reflex stays off."""
    params = load_params(ROOT / "params.yaml", ["eval.reflex_gait=[0.4, 0.2, 3.141593]"])
    scenario, gait = load_scenarios(["single_block"])[0], params.eval.reflex_gait
    plain = run_episode(params, EpisodeJob(scenario, ControllerSpec("best_fixed", gait=gait), 0, 1000)).row
    by_hand = run_episode(params, EpisodeJob(scenario, ControllerSpec("reflex_gait", gait=gait, lift_reflex=True), 0,
                                             1000)).row
    assert plain["termination"] == "stuck" and plain["distance"] < 1.0
    assert by_hand["success"] and not params.task.lift_reflex


def test_missing_policy_names_the_path_and_the_fix(tmp_path):
    params = Params()
    with pytest.raises(PolicyError, match="train-ppo") as err:
        load_policy(tmp_path / "nope", params)
    assert str(tmp_path / "nope") in str(err.value) and "\n" not in str(err.value)
    (tmp_path / "half").mkdir()
    with pytest.raises(PolicyError, match=r"policy\.json not found"):
        load_policy(tmp_path / "half", params)


def test_a_changed_heightmap_size_is_refused_with_expected_vs_found(seeing):
    smaller = seeing.model_copy(update={"sensors": seeing.sensors.model_copy(update={"heightmap_rows": 16})})
    with pytest.raises(PolicyError, match=r"heightmap_rows=32.*expected 32, found 16"):
        load_policy(Path(seeing.eval.policy_dir), smaller)
    with pytest.raises(PolicyError, match="expected a blind policy"):
        load_policy(Path(seeing.eval.policy_dir), seeing, expect_blind=True)


def test_a_retrained_encoder_with_another_latent_size_is_refused(seeing, tmp_path):
    config = json.loads((Path(seeing.eval.policy_dir) / "policy.json").read_text())
    model = ConvVAE(in_channels=1, image_size=64, latent_dim=4)
    export_encoder(model, tmp_path / "vae4", encoder_config(model, "heightmap", (32, 32)))
    moved = tmp_path / "policy"
    moved.mkdir()
    (moved / "policy").symlink_to(Path(seeing.eval.policy_dir) / "policy")
    (moved / "policy.json").write_text(json.dumps({**config, "encoder_dir": str(tmp_path / "vae4")}))
    with pytest.raises(PolicyError, match=r"not the one the policy was trained with \(expected fingerprint "):
        load_policy(moved, seeing)  # its training signature names the encoder it was trained with
    unsigned = {k: v for k, v in config.items() if k != "signature"}  # a policy.json without one: the size check
    (moved / "policy.json").write_text(json.dumps({**unsigned, "encoder_dir": str(tmp_path / "vae4")}))
    with pytest.raises(PolicyError, match=r"expected a heightmap encoder with latent_dim=8.*found heightmap with "
                                          r"latent_dim=4"):
        load_policy(moved, seeing)
    (moved / "policy.json").write_text(json.dumps({**config, "encoder_dir": str(tmp_path / "missing")}))
    with pytest.raises(PolicyError, match=re.escape(str(tmp_path / "missing"))):
        load_policy(moved, seeing)


def test_policy_features_match_training_layout(seeing):
    policy = load_policy(Path(seeing.eval.policy_dir), seeing)
    assert policy.sensors == ("heightmap",) and policy.name == "ppo+heightmap-vae8"
    env = HexapodEnv("single_block", sim=seeing.sim, cpg=seeing.cpg, sensors=seeing.sensors, task=seeing.task)
    obs, _ = env.reset(seed=3)
    embedded = TerrainEmbedding(env, policy.encoder, frame_shape=(32, 32))  # as train-ppo's workers see it
    wrapped = TerrainFeatures(DummyVecEnv([lambda: embedded]), expect_embedding=True)
    batch = {k: v[None] for k, v in embedded.observation(obs).items()}
    np.testing.assert_allclose(policy.features(obs), wrapped.features(batch), rtol=0, atol=1e-6)
    action = policy.predict(obs)
    assert action.shape == (3,) and np.all(np.abs(action) <= 1) and np.array_equal(action, policy.predict(obs))
    env.close()


def test_unknown_terrain_fails_before_any_episode(tmp_path):
    params = load_params(ROOT / "params.yaml", [f"eval.out_dir={tmp_path / 'eval'}", f"eval.policy_dir={tmp_path}"])
    with pytest.raises(TerrainError, match="unknown terrain 'nowhere'"):
        evaluate(params, extra_terrains=("nowhere",), show_progress=False)
    assert not (tmp_path / "eval").exists()


def test_gait_ranking_breaks_ties_by_distance_up_to_the_goal_then_speed():
    rows = pd.DataFrame([  # same success and cost of transport: the ties the ranking's last keys break
        {"gait": "overshoot", "success": True, "distance": 3.02, "time": 20.0, "termination": "goal"},
        {"gait": "fast", "success": True, "distance": 3.004, "time": 10.0, "termination": "goal"},
        {"gait": "far", "success": False, "distance": 2.5, "time": 40.0, "termination": "time_limit"},
        {"gait": "stuck", "success": False, "distance": 0.5, "time": 6.0, "termination": "stuck"},
    ]).assign(cost_of_transport=2.0)
    assert rank_gaits(rows, goal_distance=3.0)["gait"].tolist() == ["fast", "overshoot", "far", "stuck"]


@pytest.mark.parametrize(("gait", "termination", "legs"), [((0.25, 0.15, 1.5 * math.pi), "stuck", "front"),
                                                            ((0.25, 0.40, 1.5 * math.pi), "goal", "")])
def test_a_low_gait_stops_with_its_front_feet_at_the_face(gait, termination, legs):
    """The physical premise, read by evaluate: b = 0.15 stalls at the block's face, front feet first; b = 0.40
    crosses, and an episode that arrives names no legs. b = 0.15 lies below the floor cpg.lower: run_episode
    lowers it for a fixed gait, which holds its b the whole episode."""
    params = load_params(ROOT / "params.yaml")
    scenario = load_scenarios(["single_block"])[0]
    row = run_episode(params, EpisodeJob(scenario, ControllerSpec("fixed", gait=gait), 0, 1000)).row
    assert (row["termination"], row["stall_legs"]) == (termination, legs)
    assert row["b_mean"] == pytest.approx(gait[1])


def test_grid_gaits_may_lie_outside_the_cpg_bounds_but_must_be_positive():
    params = load_params(ROOT / "params.yaml", ["cpg.lower=[0.25,0.2,3.141593]"])
    wide = {"grid_a": (0.2, 0.45), "grid_b": (0.6,), "grid_omega": (2 * math.pi,)}  # below floors, above ceilings
    assert grid_gaits(params.model_copy(update={"eval": params.eval.model_copy(update=wide)})) == [
        (0.2, 0.6, 2 * math.pi), (0.45, 0.6, 2 * math.pi)]
    for key, values in (("grid_a", (0.2, 0.0)), ("grid_b", (-0.1,))):
        bad = params.model_copy(update={"eval": params.eval.model_copy(update={key: values})})
        with pytest.raises(ConfigError, match=rf"eval.{key}: \[{values[-1]}\] must be positive"):
            grid_gaits(bad)


def test_legs_at_faces_names_the_legs_a_face_stops():
    groups = ["front", "front", "middle", "middle", "hind", "hind"]
    faces = [1.0, 2.0]
    hind_at_first = np.array([1.85, 1.80, 1.45, 1.50, 0.98, 1.01])  # body past the face: a hind foot meets it
    assert legs_at_faces(hind_at_first, groups, faces) == "hind"
    both = np.array([1.93, 2.02, 1.45, 1.50, 0.93, 1.10])  # 7 cm before one face, 2 cm onto the other
    assert legs_at_faces(both, groups, faces) == "front+hind"
    assert legs_at_faces(np.array([0.5, 0.6, 0.1, 0.1, -0.4, -0.4]), groups, faces) == "none"  # nowhere near
    assert legs_at_faces(np.array([0.91, 0.9, 0.5, 0.5, 0.0, 0.0]), groups, faces) == "none"  # 9 cm short


def test_stall_counts_group_failed_episodes_in_the_given_order():
    rows = pd.DataFrame([
        {"terrain": "wide_block", "controller": "policy", "termination": "stuck", "stall_legs": "hind"},
        {"terrain": "wide_block", "controller": "policy", "termination": "fall", "stall_legs": "hind"},
        {"terrain": "wide_block", "controller": "policy", "termination": "stuck", "stall_legs": "front"},
        {"terrain": "wide_block", "controller": "policy", "termination": "goal", "stall_legs": None},
        {"terrain": "single_block", "controller": "open_loop", "termination": "stuck", "stall_legs": "front"},
        {"terrain": "single_block", "controller": "grid", "termination": "stuck", "stall_legs": "front"},
    ])
    order = {"terrain": ["single_block", "wide_block"], "controller": ["policy", "open_loop"]}
    assert stall_counts(rows, order) == [(("single_block", "open_loop"), 1, "front 1"),
                                         (("wide_block", "policy"), 3, "hind 2, front 1")]
    assert stall_counts(rows.drop(columns="stall_legs"), order)[1] == (("wide_block", "policy"), 3, "- 3")


def test_gait_ranking_is_the_same_whatever_order_the_workers_return_episodes_in():
    """Float sums depend on order ((0.1 + 0.2) + 0.3 != (0.3 + 0.2) + 0.1): the grid's means must not."""
    rows = pd.DataFrame([{"gait": g, "terrain": "varied", "episode": i, "success": True, "distance": 3.0 + d,
                          "time": 10.0 + d, "termination": "goal", "cost_of_transport": c}
                         for g in ("a", "b") for i, (c, d) in enumerate([(0.1, 0.1), (0.2, 0.2), (0.3, 0.3)])])
    first = rank_gaits(rows, goal_distance=3.0)
    for seed in range(5):
        shuffled = rows.sample(frac=1.0, random_state=seed)
        pd.testing.assert_frame_equal(rank_gaits(shuffled, goal_distance=3.0), first, check_exact=True)


def test_lift_is_split_between_the_last_30_cm_before_a_face_and_open_ground():
    distance = np.arange(0.05, 3.0, 0.1)  # one trace row every 0.1 m, between the window edges
    b = np.where((distance >= 0.45) & (distance <= 1.75), 0.45, 0.15)  # lifts from 0.55 m before to 0.45 m past
    trace = np.zeros((len(distance), len(TRACE_COLUMNS)), dtype=np.float32)
    trace[:, TRACE_COLUMNS.index("distance")], trace[:, TRACE_COLUMNS.index("lift")] = distance, b
    before, away = lift_before_and_away(trace, [(1.0, 1.3)])  # before: 0.7 .. 1.0 m; open: past 1.8 m
    assert before == pytest.approx(0.45) and away == pytest.approx(0.15)
    lifts_late = trace.copy()
    lifts_late[:, TRACE_COLUMNS.index("lift")] = np.where(distance >= 0.95, 0.45, 0.15)
    assert lift_before_and_away(lifts_late, [(1.0, 1.3)])[0] == pytest.approx((2 * 0.15 + 0.45) / 3)
    before, away = lift_before_and_away(trace, [])  # no block: nothing before one, everything open
    assert np.isnan(before) and away == pytest.approx(b.mean())
