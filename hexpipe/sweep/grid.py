"""The sweep's grid: conditions x seeds -> trials, each with the Params it trains and evaluates under.

A trial's Params are the sweep's base params (params.yaml + --set) with the condition's overrides, ppo.seed set to
the trial's seed, and every output folder moved under data_dir/NAME/TRIAL and report_dir/NAME/TRIAL. With
sweep.train_encoder, vae.seed is the trial's seed too, and the encoder it trains lives under
data_dir/NAME/encoders/ENCODER (report_dir/NAME/encoders/ENCODER), named by its seed and a hash of its vae settings
so that trials needing the same encoder share it.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

from hexpipe.config import ConfigError, Params, apply_overrides, parse_override

# Set per trial by the sweep: a condition may not move them, or trials would overwrite each other.
OWNED = ("ppo.seed", "ppo.out_dir", "ppo.report_dir", "eval.policy_dir", "eval.out_dir", "eval.report_dir")
# ... and these too when each trial trains its encoder (sweep.train_encoder)
OWNED_ENCODER = ("vae.seed", "vae.out_dir", "vae.report_dir", "ppo.encoder_dir")


TRIAL_SECTIONS = {"sim", "cpg", "sensors", "task", "ppo", "eval"}  # what train-ppo and evaluate read


@dataclass(frozen=True)
class Trial:
    condition: str
    seed: int
    overrides: tuple[str, ...]  # the condition's --set overrides (the sweep adds seed, folders, recording)
    params: Params

    @property
    def name(self) -> str:
        return f"{self.condition}-seed{self.seed}"

    @property
    def key(self) -> str:
        """Hash of the params the trial reads (train-ppo's and evaluate's, as in dvc.yaml): a stored result is
        reused only under the same key. collect and the sweep's own section (statistics, --cpus) do not change a
        trial; the encoder it loads is named by ppo.encoder_dir, and vae counts only when the trial trains it."""
        dump = self.params.model_dump(mode="json", include=TRIAL_SECTIONS)
        dump["collect"] = {"log_every": self.params.collect.log_every}  # evaluate's MCAP logging
        if self.params.sweep.train_encoder:
            dump["vae"] = self.params.vae.model_dump(mode="json")
        return hashlib.sha256(json.dumps(dump, sort_keys=True).encode()).hexdigest()[:16]

    @property
    def encoder(self) -> str | None:
        """The encoder the trial trains (the folder name under encoders/), or None: it loads ppo.encoder_dir."""
        return Path(self.params.vae.out_dir).name if self.params.sweep.train_encoder else None

    @property
    def cpus(self) -> int:
        return trial_cpus(self.params)


def trial_cpus(params: Params) -> int:
    """CPUs a trial reserves: its PPO env processes, or evaluate's workers if more (and its encoder's threads)."""
    return max(params.ppo.n_envs, params.eval.workers)


def trial_dirs(params: Params, name: str) -> tuple[Path, Path]:
    """(data folder, report folder) of trial `name` of the sweep params.sweep.name."""
    cfg = params.sweep
    return Path(cfg.data_dir) / cfg.name / name, Path(cfg.report_dir) / cfg.name / name


def encoder_name(params: Params) -> str:
    """'seed3-1a2b3c4d': the encoder's seed and a hash of the other vae settings that shape it (not its folders), so
    the encoders of one recipe share the hash."""
    settings = params.vae.model_dump(mode="json", exclude={"seed", "out_dir", "report_dir"})
    digest = hashlib.sha256(json.dumps(settings, sort_keys=True).encode()).hexdigest()[:8]
    return f"seed{params.vae.seed}-{digest}"


def parse_condition(text: str) -> tuple[str, tuple[str, ...]]:
    """'blind:ppo.blind=true;task.power_cost=0.1' -> ('blind', (...)); 'default:' or 'default' -> no overrides."""
    name, _, rest = text.partition(":")
    overrides = tuple(o.strip() for o in rest.split(";") if o.strip())
    if not name.strip():
        raise ConfigError(f"--condition {text!r}: expected NAME:section.key=value;section.key=value")
    return name.strip(), overrides


def expand(params: Params) -> list[Trial]:
    """Every (condition, seed) of params.sweep, seed-major (every condition's first seed, then the second, ...: a
    sweep stopped half-way has comparable conditions), each validated (ConfigError names the condition)."""
    cfg = params.sweep
    owned = OWNED + (OWNED_ENCODER if cfg.train_encoder else ())
    for condition, overrides in cfg.conditions.items():
        for text in overrides:
            key, _ = parse_override(text)
            if key in owned or key.startswith("sweep."):
                raise ConfigError(f"sweep condition '{condition}': {key} is set by the sweep for each trial")
            if key.startswith("vae.") and not cfg.train_encoder:
                raise ConfigError(f"sweep condition '{condition}': {key} changes nothing unless each trial trains "
                                  "its encoder (--train-encoder, sweep.train_encoder)")
    trials = []
    for seed in cfg.seeds:
        for condition, overrides in cfg.conditions.items():
            name = f"{condition}-seed{seed}"
            data, report = trial_dirs(params, name)
            own = [f"ppo.seed={seed}", f"ppo.out_dir={data / 'ppo'}", f"ppo.report_dir={report / 'ppo'}",
                   f"eval.policy_dir={data / 'ppo'}", f"eval.out_dir={data / 'eval'}",
                   f"eval.report_dir={report / 'eval'}"]
            if not cfg.record:
                own += ["eval.record_video=false", "eval.log_episodes=0"]
            source = f"sweep condition '{condition}'"
            if cfg.train_encoder:
                drawn = apply_overrides(params, (*overrides, f"vae.seed={seed}"), source=source)
                encoder = encoder_name(drawn)
                enc_data, enc_report = trial_dirs(params, f"encoders/{encoder}")
                own += [f"vae.seed={seed}", f"vae.out_dir={enc_data}", f"vae.report_dir={enc_report}",
                        f"ppo.encoder_dir={enc_data}"]
            applied = (*overrides, *own)
            trial_params = apply_overrides(params, applied, source=source)
            trials.append(Trial(condition, seed, tuple(overrides), trial_params))
    return trials
