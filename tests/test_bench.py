"""`hexpipe bench`'s parts: the baseline physics it compares against, and the training-rate run, at tiny budgets."""

from hexpipe.bench import BASELINE_SIM, baseline_sim, bench_env, bench_training
from hexpipe.config import Params, SimConfig


def test_baseline_is_the_physics_before_issue_12_with_everything_else_kept():
    sim = SimConfig(friction=0.8)
    base = baseline_sim(sim)
    assert (base.physics_hz, base.solver_iterations, base.position_gain) == (240, 50, 0.3)
    assert base.friction == 0.8
    # same servo bandwidth (gain x rate) as the default, so the baseline differs only in cost
    assert base.position_gain * base.physics_hz == SimConfig().position_gain * SimConfig().physics_hz
    assert set(BASELINE_SIM) <= set(SimConfig.model_fields)


def test_bench_env_reports_default_against_baseline():
    result = bench_env(Params(), ("flat",), windows=1, steps=3)
    row = result["flat"]
    assert {"default", "baseline", "physics", "heightmap", "camera"} <= set(row)
    assert row["speedup_vs_baseline"] > 0 and row["default"]["steps_per_s"] > 0


def test_bench_training_times_ppo_against_the_bare_env():
    params = Params().model_copy(update={"ppo": Params().ppo.model_copy(update={"n_steps": 16, "batch_size": 16,
                                                                                "n_epochs": 1})})
    result = bench_training(params, steps=64, terrain="flat", rounds=1)
    assert result["timesteps"] >= 64 and result["n_envs"] == 2 and result["encoder"]
    assert result["train_vs_bare"] > 0 and result["bare_env_steps_per_s"] > 0
    assert set(result["forwards"]) == {"numpy", "torch"} and result["numpy_vs_torch_forward"] > 0
    assert result["train_vs_bare"] == result["forwards"]["numpy"]["train_vs_bare"]  # the configured forward
    assert set(result["forward_us"]) == {"numpy", "torch"} and min(result["forward_us"].values()) > 0
