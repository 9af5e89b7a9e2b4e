"""PPO wiring: features built once per step (batched), tiny real training runs, checkpoints and resume."""

import json
from pathlib import Path

import numpy as np
import pytest
from stable_baselines3.common.vec_env import DummyVecEnv

from hexpipe.config import Params, load_params
from hexpipe.envs.hexapod import HexapodEnv
from hexpipe.models.vae import ConvVAE, encoder_config, export_encoder
from hexpipe.rl.features import TerrainEmbedding, TerrainFeatures
from hexpipe.rl.train import EnvClock, first_time_success_rate, train_ppo

ROOT = Path(__file__).resolve().parents[1]


class CountingEncoder:
    modality, latent_dim = "heightmap", 8

    def __init__(self):
        self.calls: list[tuple[int, ...]] = []

    def encode(self, batch):
        self.calls.append(batch.shape)
        return np.full((len(batch), 8), batch.mean(axis=(1, 2))[:, None], dtype=np.float32)


def test_each_env_embeds_its_own_frames_and_terminal_observations_keep_the_layout():
    encoder = CountingEncoder()
    task = Params().task.model_copy(update={"time_limit": 0.2})
    fns = [lambda: TerrainEmbedding(HexapodEnv("single_block", task=task), encoder, frame_shape=(32, 32))] * 2
    venv = TerrainFeatures(DummyVecEnv(fns), expect_embedding=True)
    obs = venv.reset()
    assert obs.shape == (2, 11 + 6 + 8) and venv.observation_space.shape == (25,)  # body without x, y
    for _ in range(4):  # 0.2 s = 4 steps: every env truncates on the 4th
        obs, _, dones, infos = venv.step(np.zeros((2, 3), dtype=np.float32))
    assert dones.all()
    assert all(info["terminal_observation"].shape == (25,) for info in infos)
    # the embedding is the encoder's output on the frame (CountingEncoder: the frame's mean in every latent dim)
    assert np.all(obs[:, 17:] == obs[:, 17:18])
    # one single-frame call per env per reset and step, plus the auto-reset after the last step
    assert encoder.calls == [(1, 32, 32)] * (2 * (1 + 4 + 1))
    venv.close()


def test_features_refuse_an_encoder_for_an_unobserved_sensor():
    env = HexapodEnv("flat", task=Params().task.model_copy(update={"sensors": ()}))
    with pytest.raises(ValueError, match="modality 'heightmap' is not observed"):
        TerrainEmbedding(env, CountingEncoder())
    with pytest.raises(ValueError, match="lack a terrain embedding"):
        TerrainFeatures(DummyVecEnv([lambda: env]), expect_embedding=True)
    env.close()


def tiny(tmp_path: Path, *extra: str) -> Params:
    return load_params(ROOT / "params.yaml", [
        "ppo.total_timesteps=256", "ppo.n_steps=64", "ppo.batch_size=64", "ppo.n_epochs=1",
        "ppo.checkpoint_every=128", "task.time_limit=2.0", "ppo.train_terrains=[single_block]",
        f"ppo.out_dir={tmp_path / 'ppo'}", f"ppo.report_dir={tmp_path / 'reports'}",
        f"ppo.encoder_dir={tmp_path / 'vae'}", *extra,
    ])


def test_tiny_training_with_an_encoder_writes_policy_reports_and_checkpoints(tmp_path):
    model = ConvVAE(in_channels=1, image_size=64, latent_dim=8)
    export_encoder(model, tmp_path / "vae", encoder_config(model, "heightmap", (32, 32)))
    params = tiny(tmp_path, "ppo.n_envs=2")
    metrics = train_ppo(params, show_progress=False)
    assert metrics["timesteps"] == 256
    # the env's own rate, timed on the same steps: training around it (encoder, learner) can only be slower
    assert metrics["time/bare_env_steps_per_s"] > metrics["time/train_steps_per_s"] > 0
    config = json.loads((tmp_path / "ppo" / "policy.json").read_text())
    assert config["observation_dim"] == 25 and config["modality"] == "heightmap" and not config["blind"]
    assert (tmp_path / "ppo" / "policy" / "model.zip").is_file()
    assert (tmp_path / "ppo" / "policy" / "vecnormalize.pkl").is_file()
    summary = json.loads((tmp_path / "reports" / "metrics.json").read_text())
    speed = json.loads((tmp_path / "reports" / "speed.json").read_text())
    assert 0 < speed["time"]["train_vs_bare"] < 1 and "time" not in summary  # results and timings apart
    assert summary["step"] == 256 and "success_rate" in summary["episode"]
    assert (tmp_path / "reports" / "plots" / "metrics" / "time" / "steps_per_s.tsv").is_file()


def test_resume_continues_and_changed_params_start_over(tmp_path):
    params = tiny(tmp_path, "ppo.blind=true", "ppo.n_envs=1")
    train_ppo(params, show_progress=False)
    longer = tiny(tmp_path, "ppo.blind=true", "ppo.n_envs=1", "ppo.total_timesteps=384")
    metrics = train_ppo(longer, resume=True, show_progress=False)
    assert metrics["timesteps"] == 384
    again = train_ppo(longer, resume=True, show_progress=False)  # already at total_timesteps: a no-op
    assert again == {"finished": True, "timesteps": 384}
    ckpts = sorted(p.name for p in (tmp_path / "ppo" / "checkpoints").glob("step-*"))
    assert ckpts[-1] == "step-000000384"
    other = tiny(tmp_path, "ppo.blind=true", "ppo.n_envs=1", "ppo.learning_rate=0.001")
    metrics = train_ppo(other, resume=True, show_progress=False)
    assert metrics["timesteps"] == 256  # the old checkpoint was made under other params: not resumed


def test_checkpoints_from_other_code_are_not_resumed(tmp_path, monkeypatch):
    train_ppo(tiny(tmp_path, "ppo.blind=true", "ppo.n_envs=1", "ppo.total_timesteps=384"), show_progress=False)
    monkeypatch.setattr("hexpipe.provenance.code_fingerprint", lambda: "edited-code")
    metrics = train_ppo(tiny(tmp_path, "ppo.blind=true", "ppo.n_envs=1"), resume=True, show_progress=False)
    assert metrics["timesteps"] == 256  # the 384-step checkpoint came from other code: started over


def test_timesteps_to_success_rate_is_the_first_window_that_reaches_it():
    episodes = [{"success": s, "timesteps": 100 * (i + 1)} for i, s in enumerate([0, 1, 1, 0, 1, 1, 1])]
    assert first_time_success_rate(episodes, threshold=0.6, window=3) == 300
    assert first_time_success_rate(episodes, threshold=1.0, window=3) == 700
    assert first_time_success_rate(episodes, threshold=1.0, window=8) is None


def test_env_clock_counts_every_env_step_and_only_the_time_inside_the_env():
    clock = EnvClock(DummyVecEnv([lambda: HexapodEnv("flat"), lambda: HexapodEnv("flat")]))
    clock.reset()
    for _ in range(3):
        clock.step(np.zeros((2, 3), dtype=np.float32))
    assert clock.steps == 6 and clock.seconds > 0
    assert clock.steps_per_s == pytest.approx(6 / clock.seconds)
    clock.close()


def test_a_privileged_critic_trains_resumes_and_exports_an_actor_with_the_usual_inputs(tmp_path):
    from stable_baselines3 import PPO

    from hexpipe.envs.hexapod import HexapodEnv
    from hexpipe.rl.policy import load_policy

    model = ConvVAE(in_channels=1, image_size=32, latent_dim=8)
    export_encoder(model, tmp_path / "vae", encoder_config(model, "heightmap", (32, 32)))
    params = tiny(tmp_path, "ppo.n_envs=2", "ppo.privileged_critic=true", "ppo.total_timesteps=128")
    train_ppo(params, show_progress=False)
    longer = tiny(tmp_path, "ppo.n_envs=2", "ppo.privileged_critic=true")
    assert train_ppo(longer, resume=True, show_progress=False)["timesteps"] == 256  # the checkpoint reloads
    trained = PPO.load(tmp_path / "ppo" / "policy" / "model.zip", device="cpu")
    assert trained.policy.observation_space.shape == (25 + 32 + 2,) and trained.policy.actor_dim == 25
    config = json.loads((tmp_path / "ppo" / "policy.json").read_text())
    assert config["observation_dim"] == 25 and config["privileged_critic"]
    policy = load_policy(tmp_path / "ppo", longer)  # evaluate's view: the actor alone, no privileged input
    env = HexapodEnv.from_params(policy.params, "single_block", obs_sensors=policy.sensors)
    obs, _ = env.reset(seed=0)
    x = policy.normaliser(policy.features(obs))
    hidden = np.random.default_rng(0).normal(size=(1, 34)).astype(np.float32)  # whatever the critic saw
    expected, _ = trained.policy.predict(np.concatenate([x, hidden], axis=1), deterministic=True)
    np.testing.assert_array_equal(policy.predict(obs), expected.reshape(-1))
    env.close()


def test_a_rise_readout_policy_sees_the_heads_predictions_and_evaluate_rebuilds_them(tmp_path):
    """ppo.rise_readout: 3 more inputs (the exported rise head on the latent mean), recorded in policy.json, so that
    evaluate's loader appends the same read-out whatever params it is given."""
    import torch

    from hexpipe.config import ConfigError
    from hexpipe.envs.hexapod import HexapodEnv
    from hexpipe.rl.policy import load_policy

    torch.manual_seed(0)
    model = ConvVAE(in_channels=1, image_size=32, latent_dim=8)
    head = torch.nn.Linear(8, 3)
    export_encoder(model, tmp_path / "vae", encoder_config(model, "heightmap", (32, 32)), head)
    params = tiny(tmp_path, "ppo.n_envs=1", "ppo.rise_readout=true", "ppo.total_timesteps=128")
    train_ppo(params, show_progress=False)
    config = json.loads((tmp_path / "ppo" / "policy.json").read_text())
    assert config["observation_dim"] == 28 and config["latent_dim"] == 11 and config["rise_readout"]
    policy = load_policy(tmp_path / "ppo", tiny(tmp_path, "ppo.n_envs=1"))  # params without the setting
    env = HexapodEnv.from_params(policy.params, "single_block", obs_sensors=policy.sensors)
    obs, _ = env.reset(seed=0)
    features = policy.features(obs)
    latent = features[0, 17:25]
    with torch.no_grad():
        expected = head(torch.from_numpy(latent[None])).numpy()[0]
    assert features.shape == (1, 28)
    np.testing.assert_allclose(features[0, 25:], expected, rtol=1e-5, atol=1e-6)
    env.close()
    with pytest.raises(ConfigError, match=r"rise_readout reads the terrain encoder"):
        tiny(tmp_path, "ppo.blind=true", "ppo.rise_readout=true")


def test_gsde_trains_resumes_and_exports_the_same_deterministic_actor(tmp_path):
    """ppo.use_sde: SB3's state-dependent exploration trains (with SB3's torch forward: the numpy one is a plain
    Gaussian's), resumes from its checkpoint, and exports an actor whose deterministic actions are the trained
    model's; gSDE with the asymmetric critic is refused in one line."""
    from stable_baselines3 import PPO

    from hexpipe.config import ConfigError
    from hexpipe.envs.hexapod import HexapodEnv
    from hexpipe.rl.policy import load_policy

    model = ConvVAE(in_channels=1, image_size=32, latent_dim=8)
    export_encoder(model, tmp_path / "vae", encoder_config(model, "heightmap", (32, 32)))
    sde = ("ppo.n_envs=1", "ppo.use_sde=true", "ppo.sde_sample_freq=4", "ppo.log_std_init=-2")
    train_ppo(tiny(tmp_path, *sde, "ppo.total_timesteps=128"), show_progress=False)
    longer = tiny(tmp_path, *sde)
    assert train_ppo(longer, resume=True, show_progress=False)["timesteps"] == 256  # the checkpoint reloads
    trained = PPO.load(tmp_path / "ppo" / "policy" / "model.zip", device="cpu")
    assert trained.use_sde and trained.sde_sample_freq == 4
    assert trained.policy.log_std.shape == (64, 3)  # one noise scale per hidden feature and action
    policy = load_policy(tmp_path / "ppo", longer)
    env = HexapodEnv.from_params(policy.params, "single_block", obs_sensors=policy.sensors)
    obs, _ = env.reset(seed=0)
    for _ in range(3):
        expected, _ = trained.policy.predict(policy.normaliser(policy.features(obs)), deterministic=True)
        action = policy.predict(obs)
        np.testing.assert_array_equal(action, expected.reshape(-1))
        obs, *_ = env.step(action)
    env.close()
    with pytest.raises(ConfigError, match="use_sde with privileged_critic"):
        tiny(tmp_path, *sde, "ppo.privileged_critic=true")


def test_a_policy_runs_only_under_the_action_order_it_was_trained_with(tmp_path):
    from hexpipe.rl.policy import PolicyError, load_policy

    blind = ("ppo.n_envs=1", "ppo.blind=true", "ppo.total_timesteps=64")
    second = tiny(tmp_path, *blind, "cpg.action_order=2")  # the paper's, not the pipeline's default (1)
    train_ppo(second, show_progress=False)
    assert load_policy(tmp_path / "ppo", second).config["cpg"]["action_order"] == 2
    assert load_policy(tmp_path / "ppo").params.cpg.action_order == 2  # run with its own settings: the trained order
    with pytest.raises(PolicyError, match=r"trained with cpg\.action_order=2 \(its actions are the second "
                                          r"derivatives of a, b, omega\), params now have 1") as err:
        load_policy(tmp_path / "ppo", tiny(tmp_path, *blind))
    assert "\n" not in str(err.value)


def test_the_lift_price_ramps_in_through_every_training_env():
    """ppo.lift_cost_ramp: the callback reaches HexapodEnv through the training stack (worker processes and the
    curriculum wrapper) and sets the share of task.lift_cost that the next steps charge."""
    from types import SimpleNamespace

    from hexpipe.rl.callbacks import LiftCostRamp
    from hexpipe.rl.train import make_vec_env

    params = load_params(ROOT / "params.yaml", ["task.lift_cost=10", "cpg.initial=[0.8,0.4,4.319690]",
                                                 "ppo.lift_cost_ramp=[0.25,0.75]", "ppo.total_timesteps=400"])
    venv = make_vec_env(params, ("flat",), 2, None, False, 0)
    try:
        venv.reset()
        model = SimpleNamespace(num_timesteps=0, get_env=lambda: venv, logger=None)
        ramp = LiftCostRamp(100, 300)
        ramp.init_callback(model)
        charged = []
        for steps in (0, 100, 200, 300, 400):
            model.num_timesteps = steps
            ramp.on_rollout_start()
            _, _, _, infos = venv.step(np.zeros((2, 3), dtype=np.float32))
            charged.append([info["reward_terms"]["lift"] for info in infos])
    finally:
        venv.close()
    # b holds 0.4, 0.2 above its floor: the whole price is -10 * 0.2 = -2 per step
    assert np.allclose(charged, [[0.0, 0.0], [0.0, 0.0], [-1.0, -1.0], [-2.0, -2.0], [-2.0, -2.0]])


def test_a_lift_price_ramp_must_rise():
    with pytest.raises(ValueError, match="lift_cost_ramp"):
        load_params(ROOT / "params.yaml", ["ppo.lift_cost_ramp=[0.8,0.2]"])


def test_training_under_a_lift_price_ramp_charges_nothing_before_it_starts(tmp_path):
    params = tiny(tmp_path, "ppo.blind=true", "ppo.n_envs=1", "task.lift_cost=10", "ppo.lift_cost_ramp=[0.5,0.75]",
                  "ppo.train_terrains=[flat]")
    train_ppo(params, show_progress=False)
    episodes = [json.loads(line) for line in (tmp_path / "reports" / "episodes.jsonl").read_text().splitlines()]
    before = [e["reward_terms"]["lift"] for e in episodes if e["timesteps"] <= 128]
    after = [e["reward_terms"]["lift"] for e in episodes if e["timesteps"] > 192]
    assert before and after and all(v == 0.0 for v in before) and min(after) < 0.0
