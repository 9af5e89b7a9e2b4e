"""train-ppo --resume: only the same params, code and encoder, never a longer run, a finished run is a no-op,
and a corrupt newest checkpoint falls back to the one before it."""

import json
from pathlib import Path

import torch

from hexpipe.config import Params, load_params
from hexpipe.models.vae import ConvVAE, encoder_config, export_encoder
from hexpipe.rl.train import train_ppo

ROOT = Path(__file__).resolve().parents[1]


def tiny(tmp_path: Path, *extra: str) -> Params:
    return load_params(ROOT / "params.yaml", [
        "ppo.total_timesteps=256", "ppo.n_steps=64", "ppo.batch_size=64", "ppo.n_epochs=1", "ppo.n_envs=1",
        "ppo.checkpoint_every=128", "task.time_limit=2.0", "ppo.train_terrains=[single_block]",
        f"ppo.out_dir={tmp_path / 'ppo'}", f"ppo.report_dir={tmp_path / 'reports'}",
        f"ppo.encoder_dir={tmp_path / 'vae'}", *extra,
    ])


def export(tmp_path: Path, seed: int) -> None:
    torch.manual_seed(seed)
    model = ConvVAE(in_channels=1, image_size=64, latent_dim=8)
    export_encoder(model, tmp_path / "vae", encoder_config(model, "heightmap", (32, 32)))


def steps(tmp_path: Path) -> list[int]:
    return sorted(int(p.name[5:]) for p in (tmp_path / "ppo" / "checkpoints").glob("step-*"))


def test_a_retrained_encoder_is_not_resumed(tmp_path, capsys):
    export(tmp_path, seed=0)
    train_ppo(tiny(tmp_path, "ppo.total_timesteps=128"), show_progress=False)
    export(tmp_path, seed=7)  # `hexpipe train-vae --set vae.seed=7`: same params, another encoder
    metrics = train_ppo(tiny(tmp_path), resume=True, show_progress=False)
    assert metrics["timesteps"] == 256 and metrics["time/train_steps_per_s"] > 0
    assert "other params, code or encoder; starting over" in capsys.readouterr().err
    assert steps(tmp_path) == [128, 256]  # 128 is this run's own, not the old run's


def test_resuming_a_finished_run_is_a_no_op(tmp_path):
    params = tiny(tmp_path, "ppo.blind=true")
    train_ppo(params, show_progress=False)
    policy = tmp_path / "ppo" / "policy" / "model.zip"
    before = policy.stat().st_mtime_ns, (tmp_path / "reports" / "metrics.json").read_text()
    assert train_ppo(params, resume=True, show_progress=False) == {"finished": True, "timesteps": 256}
    assert (policy.stat().st_mtime_ns, (tmp_path / "reports" / "metrics.json").read_text()) == before


def test_a_shorter_budget_never_reuses_a_longer_run(tmp_path, capsys):
    """The README's DVC flow: a long run, then `dvc exp run -S ppo.total_timesteps=<less>` (train-ppo --resume)."""
    train_ppo(tiny(tmp_path, "ppo.blind=true", "ppo.total_timesteps=384"), show_progress=False)
    assert steps(tmp_path) == [256, 384]
    metrics = train_ppo(tiny(tmp_path, "ppo.blind=true", "ppo.total_timesteps=128"), resume=True, show_progress=False)
    assert metrics["timesteps"] == 128  # trained afresh, not the 384-step policy reported as a 128-step one
    assert "beyond this run's 128 steps" in capsys.readouterr().err
    assert json.loads((tmp_path / "ppo" / "policy.json").read_text())["timesteps"] == 128
    # a budget between two checkpoints resumes from the one below it
    train_ppo(tiny(tmp_path, "ppo.blind=true", "ppo.total_timesteps=384"), show_progress=False)
    metrics = train_ppo(tiny(tmp_path, "ppo.blind=true", "ppo.total_timesteps=320"), resume=True, show_progress=False)
    assert metrics["timesteps"] == 320 and "resuming from" in capsys.readouterr().err


def test_a_corrupt_newest_checkpoint_falls_back_to_the_previous_one(tmp_path, capsys):
    train_ppo(tiny(tmp_path, "ppo.blind=true", "ppo.total_timesteps=384"), show_progress=False)
    (tmp_path / "ppo" / "checkpoints" / "step-000000384" / "model.zip").write_bytes(b"torn write")
    metrics = train_ppo(tiny(tmp_path, "ppo.blind=true", "ppo.total_timesteps=448"), resume=True, show_progress=False)
    err = capsys.readouterr().err
    assert "step-000000384" in err and "unreadable" in err and "falling back to step-000000256" in err
    assert "resuming from" in err and metrics["timesteps"] == 448
    # every checkpoint corrupt: start over, said so
    for ckpt in (tmp_path / "ppo" / "checkpoints").glob("step-*"):
        (ckpt / "model.zip").write_bytes(b"")
    metrics = train_ppo(tiny(tmp_path, "ppo.blind=true", "ppo.total_timesteps=512"), resume=True, show_progress=False)
    assert metrics["timesteps"] == 512 and "starting over" in capsys.readouterr().err
