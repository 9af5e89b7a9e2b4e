"""Running a trained policy: `hexpipe.load_policy` (the README's snippet), weights-only files, and model files that
are corrupt or crafted to run code."""

import json
import os
import pickle
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch
from typer.testing import CliRunner

import hexpipe
from hexpipe.cli import app
from hexpipe.config import apply_overrides, load_params
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.models.vae import ConvVAE, EncoderError, encoder_config, export_encoder, load_encoder
from hexpipe.models.weights import WeightsError, load_state_dict
from hexpipe.rl.policy import PolicyError, load_policy
from hexpipe.rl.train import train_ppo

ROOT = Path(__file__).resolve().parents[1]
TINY_PPO = ["ppo.total_timesteps=256", "ppo.n_envs=1", "ppo.train_terrains=[single_block]", "ppo.n_steps=128",
            "ppo.batch_size=64", "ppo.n_epochs=1", "task.time_limit=2.0"]


@pytest.fixture(scope="module")
def seeing(tmp_path_factory) -> Path:
    """A tiny policy that sees the height map through an (untrained) VAE encoder; returns its folder."""
    root = tmp_path_factory.mktemp("seeing")
    model = ConvVAE(in_channels=1, image_size=64, latent_dim=8)
    export_encoder(model, root / "vae", encoder_config(model, "heightmap", (32, 32)))
    params = load_params(ROOT / "params.yaml", [*TINY_PPO, f"ppo.out_dir={root / 'ppo'}",
                                                f"ppo.report_dir={root / 'report'}", f"ppo.encoder_dir={root / 'vae'}"])
    train_ppo(params, show_progress=False)
    return root / "ppo"


class WritesMarker:
    """Unpickling this calls Path.touch(marker): it proves code from a model file ran."""

    def __init__(self, marker: Path):
        self.marker = marker

    def __reduce__(self):
        return (Path.touch, (self.marker,))


def crafted_files(marker: Path) -> dict[str, bytes]:
    """Model files that run code when unpickled: a raw pickle, and a torch zip file that holds one."""
    buffer = __import__("io").BytesIO()
    torch.save({"weight": WritesMarker(marker)}, buffer)
    return {"pickle": pickle.dumps(WritesMarker(marker)), "torch-zip": buffer.getvalue()}


def copy_policy(src: Path, dst: Path) -> Path:
    """A copy of a trained policy folder (its encoder stays where policy.json says)."""
    import shutil

    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("checkpoints"))
    return dst


def test_the_weights_only_policy_acts_exactly_as_the_sb3_zip_and_vecnormalize(seeing):
    from stable_baselines3 import PPO

    policy = hexpipe.load_policy(seeing)
    assert policy.name == "ppo+heightmap-vae8" and policy.sensors == ("heightmap",)
    model = PPO.load(seeing / "policy" / "model.zip", device="cpu")
    with (seeing / "policy" / "vecnormalize.pkl").open("rb") as f:
        normaliser = pickle.load(f)  # our own file, written by the training above
    env = HexapodEnv("single_block", **policy.env_kwargs)
    obs, _ = env.reset(seed=5)
    try:
        for _ in range(15):
            action = policy.predict(obs)
            expected, _ = model.predict(normaliser.normalize_obs(policy.features(obs)), deterministic=True)
            np.testing.assert_array_equal(action, expected.reshape(-1).astype(np.float32))
            obs, *_ = env.step(action)
    finally:
        env.close()
    weights = json.loads((seeing / "policy" / "weights.json").read_text())
    assert weights["observation_dim"] == 25 and weights["net_arch"] == [64, 64] and weights["activation"] == "Tanh"


def test_the_readme_snippet_runs(seeing, tmp_path):
    readme = (ROOT / "README.md").read_text()
    (snippet,) = [b for b in re.findall(r"```python\n(.*?)```", readme, flags=re.S) if "hexpipe.load_policy(" in b]
    assert '"data/models/ppo"' in snippet  # the default ppo.out_dir, as after `make repro`
    (tmp_path / "data" / "models").mkdir(parents=True)
    (tmp_path / "data" / "models" / "ppo").symlink_to(seeing)
    # one torch thread: a single observation gains nothing from more, and on a busy 2-core machine two threads
    # made each predict() 8x slower
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}
    run = subprocess.run([sys.executable, "-c", snippet], cwd=tmp_path, env=env, capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 0, run.stderr
    assert re.search(r"^(goal|stuck|fall|nonfinite|time_limit) -?\d+\.\d\d m in \d+\.\d s$", run.stdout, flags=re.M)


def test_load_policy_without_params_uses_the_training_settings(seeing):
    policy = load_policy(seeing)  # params from policy.json
    trained = json.loads((seeing / "policy.json").read_text())
    assert policy.params.sensors.model_dump(mode="json") == trained["sensors"]
    assert policy.env_kwargs["task"].sensors == ("heightmap",) and not policy.drift


def test_a_policy_recorded_before_lift_follows_runs_without_it(seeing, tmp_path):
    """policy.json files written before `cpg.lift_follows` existed lack it: those policies trained without it."""
    policy_dir = copy_policy(seeing, tmp_path / "ppo")
    config = json.loads((policy_dir / "policy.json").read_text())
    assert config["cpg"]["lift_follows"] is True  # today's default
    del config["cpg"]["lift_follows"]
    (policy_dir / "policy.json").write_text(json.dumps(config))
    assert load_policy(policy_dir).params.cpg.lift_follows is False
    now = load_params(ROOT / "params.yaml")
    assert "cpg.lift_follows: False -> True" in load_policy(policy_dir, now).drift


def test_a_policy_sees_only_the_map_reference_it_was_trained_with(seeing, tmp_path):
    """policy.json files written before `sensors.heightmap_reference` existed lack it: those policies saw the map
    from the stance plane, so they run under "stance" and are refused under "ground", in one line."""
    policy_dir = copy_policy(seeing, tmp_path / "ppo")
    config = json.loads((policy_dir / "policy.json").read_text())
    assert config["sensors"]["heightmap_reference"] == "stance"
    del config["sensors"]["heightmap_reference"]
    (policy_dir / "policy.json").write_text(json.dumps(config))
    assert load_policy(policy_dir).params.sensors.heightmap_reference == "stance"
    now = load_params(ROOT / "params.yaml")
    assert load_policy(policy_dir, now).params.sensors.heightmap_reference == "stance"
    ground = apply_overrides(now, ["sensors.heightmap_reference=ground"])
    with pytest.raises(PolicyError, match=r"trained with sensors\.heightmap_reference=stance, params now have ground"):
        load_policy(policy_dir, ground)


def test_a_policy_refuses_an_encoder_retrained_after_it(seeing, tmp_path):
    """`dvc repro` retrains the VAE in place: a policy trained on the old one must not silently read the new one's
    latents (same modality and size, another meaning). Its encoder's copy, pointed at by policy.json, runs."""
    import shutil

    policy_dir = copy_policy(seeing, tmp_path / "ppo")
    config = json.loads((policy_dir / "policy.json").read_text())
    shutil.copytree(config["encoder_dir"], tmp_path / "vae_copy")
    torch.manual_seed(1)
    other = ConvVAE(in_channels=1, image_size=64, latent_dim=8)  # same shape, other weights: a retrained VAE
    export_encoder(other, tmp_path / "vae_new", encoder_config(other, "heightmap", (32, 32)))
    (policy_dir / "policy.json").write_text(json.dumps({**config, "encoder_dir": str(tmp_path / "vae_new")}))
    with pytest.raises(PolicyError) as info:
        load_policy(policy_dir)
    message = str(info.value)
    assert "\n" not in message and "not the one the policy was trained with" in message
    assert str(tmp_path / "vae_new") in message and config["signature"].split("-")[1] in message
    (policy_dir / "policy.json").write_text(json.dumps({**config, "encoder_dir": str(tmp_path / "vae_copy")}))
    assert load_policy(policy_dir).name == "ppo+heightmap-vae8"


def test_evaluate_and_play_never_unpickle_the_sb3_files(seeing, tmp_path):
    """A crafted vecnormalize.pkl and model.zip (kept for --resume) are not read when a policy is loaded to run."""
    policy_dir = copy_policy(seeing, tmp_path / "ppo")
    marker = tmp_path / "ran"
    (policy_dir / "policy" / "vecnormalize.pkl").write_bytes(crafted_files(marker)["pickle"])
    (policy_dir / "policy" / "model.zip").write_bytes(crafted_files(marker)["torch-zip"])
    policy = load_policy(policy_dir)
    assert policy.predict(_observation(policy)).shape == (3,)
    assert not marker.exists()


@pytest.mark.parametrize("kind", ["random", "empty", "pickle", "torch-zip"])
@pytest.mark.parametrize("target", ["policy/weights.pt", "encoder.pt"])
def test_a_corrupt_or_crafted_weights_file_is_one_line_and_runs_nothing(seeing, tmp_path, kind, target):
    policy_dir = copy_policy(seeing, tmp_path / "ppo")
    marker = tmp_path / "ran"
    contents = {"random": np.random.default_rng(0).bytes(4096), "empty": b"", **crafted_files(marker)}[kind]
    if target == "encoder.pt":
        vae = Path(json.loads((policy_dir / "policy.json").read_text())["encoder_dir"])
        encoder_dir = tmp_path / "vae"
        encoder_dir.mkdir()
        (encoder_dir / "encoder.json").write_text((vae / "encoder.json").read_text())
        (encoder_dir / "encoder.pt").write_bytes(contents)
        config = json.loads((policy_dir / "policy.json").read_text())
        (policy_dir / "policy.json").write_text(json.dumps({**config, "encoder_dir": str(encoder_dir)}))
        bad = encoder_dir / "encoder.pt"
        with pytest.raises(EncoderError) as direct:
            load_encoder(encoder_dir)
        assert str(bad) in str(direct.value) and "\n" not in str(direct.value)
    else:
        bad = policy_dir / "policy" / "weights.pt"
        bad.write_bytes(contents)
    with pytest.raises(PolicyError) as err:
        load_policy(policy_dir)
    message = str(err.value)
    assert str(bad) in message and "\n" not in message and "weights_only=False" not in message
    if kind == "empty":
        assert "empty" in message
    if kind in ("pickle", "torch-zip"):
        assert "nothing was run" in message
    result = CliRunner().invoke(app, ["play", "--params", str(ROOT / "params.yaml"), "--policy", str(policy_dir)])
    assert result.exit_code == 2 and "Traceback" not in result.output and "Aborted" not in result.output
    assert str(bad.name) in result.output.strip().splitlines()[-1]
    assert not marker.exists()


def test_weights_that_do_not_fit_their_description_are_one_line(seeing, tmp_path):
    policy_dir = copy_policy(seeing, tmp_path / "ppo")
    spec = policy_dir / "policy" / "weights.json"
    good = json.loads(spec.read_text())
    for change, expected in [
        ({"net_arch": [32, 32]}, "does not match"),
        ({"activation": "os.system"}, "activation 'os.system' is not one of"),
        ({"observation_normalisation": {"mean": [0.0], "var": [1.0], "epsilon": 1e-8, "clip": 10.0}},
         "observation_normalisation needs mean and var of length 25"),
        ({"format_version": 99}, "format_version 99"),
    ]:
        spec.write_text(json.dumps({**good, **change}))
        with pytest.raises(PolicyError, match=re.escape(expected)) as err:
            load_policy(policy_dir)
        assert "\n" not in str(err.value)
    spec.write_text("[1, 2")
    with pytest.raises(PolicyError, match=r"weights\.json: unreadable"):
        load_policy(policy_dir)
    (policy_dir / "policy" / "weights.pt").unlink()
    with pytest.raises(PolicyError, match=r"weights\.pt not found .*train-ppo"):
        load_policy(policy_dir)


def test_load_state_dict_accepts_only_named_tensors(tmp_path):
    torch.save({"w": torch.ones(2)}, tmp_path / "ok.pt")
    assert torch.equal(load_state_dict(tmp_path / "ok.pt")["w"], torch.ones(2))
    torch.save([torch.ones(2)], tmp_path / "list.pt")
    with pytest.raises(WeightsError, match="expected a mapping of names to tensors, found list"):
        load_state_dict(tmp_path / "list.pt")
    with pytest.raises(WeightsError, match="not found"):
        load_state_dict(tmp_path / "missing.pt")


def _observation(policy) -> dict[str, np.ndarray]:
    env = HexapodEnv("flat", **policy.env_kwargs)
    try:
        obs, _ = env.reset(seed=0)
    finally:
        env.close()
    return obs
