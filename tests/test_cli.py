"""Typed config and the CLI: overrides, and one-line errors (never a traceback) for bad input."""

import math
from pathlib import Path

import pytest
from typer.testing import CliRunner

from hexpipe.cli import app
from hexpipe.config import ConfigError, Params, load_params

ROOT = Path(__file__).resolve().parents[1]
runner = CliRunner()


def _flat(tree, prefix=""):
    if isinstance(tree, dict):
        return {k: v for key, sub in tree.items() for k, v in _flat(sub, f"{prefix}{key}.").items()}
    if isinstance(tree, list | tuple):
        return {k: v for i, sub in enumerate(tree) for k, v in _flat(sub, f"{prefix}{i}.").items()}
    return {prefix[:-1]: tree}


# Where the pipeline's params.yaml departs from the code defaults, on purpose (hexpipe/config.py's docstring): the
# `pin138_t150` recipe since 2026-12-07 (a and omega pinned at 0.8 and 1.375 pi, b steered through its rate, both
# reflexes, a teacher of 150 scaled by relief, the stride reflex, a power price of 0.4, the fall check at 0.04 m, one
# PPO candidate, the reflex gait in the evaluation), while the code keeps the general CPG and a bare robot for the
# unit tests and library users. Keys are flattened; a value may be a subtree.
PIPELINE_ONLY = {"cpg.initial.0": 0.8, "cpg.initial.2": 1.375 * math.pi, "cpg.lower.0": 0.8,
                 "cpg.lower.2": 1.375 * math.pi, "cpg.upper.0": 0.8, "cpg.upper.2": 1.375 * math.pi,
                 "cpg.action_order": 1, "sim.elevator_gain": 2.5, "sim.heading_gain": 1.0, "task.fall_height": 0.04,
                 "task.lift_reflex_zone": (0.6, 1.05), "task.lift_reflex_relief": 0.1, "task.lift_teacher": 150.0,
                 "task.stride_reflex": 0.35, "task.power_cost": 0.4, "ppo.candidates": 1,
                 "ppo.validation_episodes": 0, "eval.reflex_gait": (0.8, 0.2, 1.375 * math.pi)}


def test_params_yaml_matches_the_code_defaults():
    """params.yaml documents the defaults; only pi-derived values are rounded there, and PIPELINE_ONLY's keys hold
    the pipeline's own values."""
    in_file, defaults = _flat(load_params(ROOT / "params.yaml").model_dump()), _flat(Params().model_dump())
    expected = {key: value for key, value in defaults.items() if key not in PIPELINE_ONLY}
    for key, value in PIPELINE_ONLY.items():
        expected.update(_flat(value, f"{key}."))
    assert in_file.keys() == expected.keys()
    for key, value in expected.items():
        assert in_file[key] == (pytest.approx(value, rel=1e-6) if isinstance(value, float) else value), key
    assert all(defaults[key] != pytest.approx(value, rel=1e-6) for key, value in PIPELINE_ONLY.items())


def test_overrides_are_typed_and_nested():
    p = load_params(ROOT / "params.yaml", ["ppo.n_envs=4", "ppo.train_terrains=[flat, rough]", "task.sensors=[rgb]"])
    assert p.ppo.n_envs == 4 and p.ppo.train_terrains == ("flat", "rough") and p.task.sensors == ("rgb",)
    assert p.task.randomization.friction == (0.6, 1.2)
    p = load_params(ROOT / "params.yaml", ["task.randomization.friction=[0.4, 1.5]"])
    assert p.task.randomization.friction == (0.4, 1.5)


@pytest.mark.parametrize(
    ("override", "expected"),
    [
        ("ppo.foo=1", "unknown key 'ppo.foo'; allowed here: batch_size"),
        ("ppo.n_envs=zero", "ppo.n_envs"),
        ("ppo.n_envs=0", "greater than or equal to 1"),
        ("cpg.initial=[0.8, 0.9, 4.319690]", "b: need 0 < lower"),
        ("cpg.fall_rate_limit=[1.0, 0.0, 10.0]", "fall_rate_limit must be positive"),
        ("sim.control_hz=7", "control_hz=7 must divide physics_hz=120"),
        ("task.sensors=[lidar]", "task.sensors[0]"),
        ("nosuchsection.x=1", "unknown key 'nosuchsection'"),
        ("ppo", "expected section.key=value"),
        ("ppo.train_terrains=[flat, rough, stairs]", "train_terrains has 3 terrains but n_envs=2"),
        ("ppo.train_terrains=[]", "train_terrains is empty"),
        ("task.power_cost=-0.1", "task.power_cost"),
        ("eval.reflex_gait=[0.4, 0.5, 3.141593]", "eval.reflex_gait's b (0.5) must lie below cpg.upper's b"),
        ("eval.reflex_gait=[0.4, 0.2]", "eval.reflex_gait"),
        ("task.failure_penalty=-5", "task.failure_penalty"),
        ("collect.cpg_lower=[0.4, 0.2, 3.141593]", "collect.cpg_lower and collect.cpg_upper go together"),
        ("collect.action_order=3", "collect.action_order"),
    ],
)
def test_bad_overrides_name_the_key(override, expected):
    with pytest.raises(ConfigError, match=None) as err:
        load_params(ROOT / "params.yaml", [override])
    assert expected in str(err.value) and "\n" not in str(err.value)


def test_collect_gait_bounds_must_be_ordered():
    with pytest.raises(ConfigError) as err:
        load_params(ROOT / "params.yaml", ["collect.cpg_lower=[0.4, 0.2, 3.141593]",
                                           "collect.cpg_upper=[0.3, 0.5, 3.141593]"])
    assert "collect.cpg_lower/cpg_upper a: need 0 < lower (0.4) <= upper (0.3)" in str(err.value)
    assert "\n" not in str(err.value)


def test_cli_reports_bad_input_in_one_line(tmp_path):
    bad_yaml = tmp_path / "p.yaml"
    bad_yaml.write_text("sim: [unclosed\n")
    cases = [
        (["bench", "--set", "sim.nope=1"], "unknown key 'sim.nope'"),
        (["bench", "--params", str(tmp_path / "missing.yaml")], "params file not found"),
        (["bench", "--params", str(bad_yaml)], "not valid YAML"),
        (["bench", "--terrains", "nowhere_land"], "nowhere_land"),
        (["train-vae", "--set", f"vae.data_dir={tmp_path / 'empty'}"], "empty"),
        (["train-ppo", "--set", f"ppo.encoder_dir={tmp_path / 'none'}"], "none"),
    ]
    for args, expected in cases:
        result = runner.invoke(app, args)
        assert result.exit_code == 2, (args, result.output)
        assert expected in result.output and "Traceback" not in result.output, (args, result.output)


def test_help_lists_the_stages():
    result = runner.invoke(app, ["--help"])
    for command in ("collect", "train-vae", "train-ppo", "evaluate", "bench"):
        assert command in result.output


def test_default_omega_is_three_quarters_hertz():
    assert Params().cpg.initial[2] == pytest.approx(1.5 * math.pi)


def test_bracketed_input_is_echoed_as_typed():
    """rich reads [word] as a style tag: a terrain named [flat] or an override holding [flat] must still show."""
    result = runner.invoke(app, ["bench", "--terrains", "[flat]"])
    assert result.exit_code == 2 and "unknown terrain '[flat]'" in result.output, result.output
    result = runner.invoke(app, ["sweep", "--dry-run", "--seeds", "0", "--condition", "x:ppo.train_terrains=[flat]"])
    assert result.exit_code == 0 and "x-seed0: ppo.train_terrains=[flat]" in result.output, result.output
