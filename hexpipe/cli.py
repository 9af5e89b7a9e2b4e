"""The `hexpipe` command line: one command per pipeline stage, plus benchmarks.

This is the only place that reads params.yaml; every command takes `--params PATH` and repeatable
`--set section.key=value` overrides, turns them into a typed `Params` once and passes the sections down.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape

from hexpipe.atomic import write_json
from hexpipe.config import ConfigError, Params, load_params

app = typer.Typer(
    no_args_is_help=True, add_completion=False, pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
    help="hexpipe: terrain-adaptive CPG gaits for a hexapod (collect -> train-vae -> train-ppo -> evaluate).",
)
console = Console(stderr=True)

ParamsOpt = Annotated[Path, typer.Option("--params", help="params file (YAML)")]
SetOpt = Annotated[
    list[str] | None, typer.Option("--set", help="override a param: section.key=value (repeatable)")
]


def _user_errors() -> tuple[type[Exception], ...]:
    """Errors caused by bad input: shown as one line, never as a traceback (imported late: they pull in torch)."""
    from hexpipe.evaluation.video import VideoError
    from hexpipe.models.vae import EncoderError
    from hexpipe.models.vae_data import VaeDataError
    from hexpipe.models.weights import WeightsError
    from hexpipe.paths import OutputError
    from hexpipe.play import PlayError
    from hexpipe.recording.reader import RecordingError
    from hexpipe.rl.policy import PolicyError
    from hexpipe.sim.terrain import TerrainError

    # OSError last: an unreadable input or a full disk is the user's to fix, and its message names the path
    return (ConfigError, FileNotFoundError, TerrainError, EncoderError, VaeDataError, RecordingError, PolicyError,
            VideoError, WeightsError, PlayError, OutputError, OSError)


@contextmanager
def user_errors() -> Iterator[None]:
    try:
        yield
    except KeyboardInterrupt:  # first: evaluating _user_errors() imports torch, seconds after a Ctrl-C
        console.print("[yellow]interrupted[/yellow]: completed outputs are kept; rerun to finish")
        raise typer.Exit(130) from None
    except _user_errors() as exc:
        message = escape(" ".join(str(exc).split()))  # a value such as [flat] is text here, not a style tag
        console.print(f"[red]error:[/red] {message}", highlight=False, soft_wrap=True)
        raise typer.Exit(2) from None


def _print_version(value: bool) -> None:
    if value:
        from hexpipe import __version__

        print(f"hexpipe {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool, typer.Option("--version", callback=_print_version, is_eager=True, help="print the version and exit")
    ] = False,
) -> None:
    """hexpipe: terrain-adaptive CPG gaits for a hexapod (collect -> train-vae -> train-ppo -> evaluate)."""


def load(params: Path, overrides: list[str] | None) -> Params:
    with user_errors():
        return load_params(params, overrides or [])


def writable(*folders: str | Path) -> None:
    """Refuse to start a stage whose output folders cannot be written (one line, before any work)."""
    from hexpipe.paths import check_writable

    with user_errors():
        check_writable(*folders)


@app.command()
def collect(
    params: ParamsOpt = Path("params.yaml"),
    set_: SetOpt = None,
    report: Annotated[Path, typer.Option(help="JSON report (throughput beside it: NAME_speed.json)")] = Path(
        "reports/collect.json"),
) -> None:
    """Random-policy rollouts over the terrain mix, logged to MCAP (RGB, height map, TF, scene, CPG, joints)."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn

    from hexpipe.collect import SPEED_KEYS, check_manifest
    from hexpipe.collect import collect as run_collect
    from hexpipe.speed import beside, split

    cfg = load(params, set_)
    writable(cfg.collect.out_dir, report.parent)
    with user_errors():
        check_manifest(cfg)  # before the progress bar: a bad manifest is one line
    with Progress("[bold]collect", BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(), console=console) as bar:
        task = bar.add_task("episodes", total=cfg.collect.episodes)
        with user_errors():
            result = run_collect(cfg, on_episode=lambda done, total: bar.update(task, completed=done, total=total),
                                 say=lambda note: console.print(note, highlight=False, markup=False))
    results, speed = split(result, SPEED_KEYS)  # dvc metrics diff shows results, not timing noise
    write_json(beside(report), speed)
    write_json(report, results)
    rate = result.get("logging_rate_vs_bare")
    console.print(
        f"collect: {result['episodes']} episodes, {result['frames']} frames, {result['bytes'] / 1e6:.1f} MB in "
        f"{cfg.collect.out_dir}; "
        + (f"logging keeps {rate:.0%} of the bare env rate" if rate else "every episode was already there")
    )


@app.command("train-vae")
def train_vae_cmd(params: ParamsOpt = Path("params.yaml"), set_: SetOpt = None) -> None:
    """Train the VAE on the collected frames (vae.modality: rgb or heightmap) and export the frozen encoder."""
    from hexpipe.models.train_vae import train_vae

    cfg = load(params, set_)
    writable(cfg.vae.out_dir, cfg.vae.report_dir)
    with user_errors():
        metrics = train_vae(cfg.vae)
    shown = {k: round(v, 4) for k, v in metrics.items() if k in ("val/loss", "probe_accuracy", "probe_baseline")}
    console.print(f"train-vae: {shown}; encoder in {cfg.vae.out_dir}")


@app.command("train-ppo")
def train_ppo_cmd(
    params: ParamsOpt = Path("params.yaml"),
    set_: SetOpt = None,
    resume: Annotated[bool, typer.Option(help="continue from the newest checkpoint in ppo.out_dir")] = False,
) -> None:
    """Train PPO on the CPG parameters with the frozen terrain encoder (or blind, ppo.blind=true); with
    ppo.candidates > 1, train that many seeds and keep the best on held-out validation episodes."""
    from hexpipe.rl.selection import train_policy

    cfg = load(params, set_)
    writable(cfg.ppo.out_dir, cfg.ppo.report_dir)
    with user_errors():
        metrics = train_policy(cfg, resume=resume, say=lambda line: console.print(line, highlight=False))
    chosen = (f"; kept seed {metrics['selection/chosen_seed']} of {cfg.ppo.candidates}" if cfg.ppo.candidates > 1
              else "")
    if metrics.get("finished"):
        console.print(f"train-ppo: nothing to do: the run in {cfg.ppo.out_dir} already reached "
                      f"{metrics['timesteps']} steps under the same params, code and encoder (raise "
                      f"ppo.total_timesteps to train on){chosen}")
        return
    rate = metrics.get("time/train_steps_per_s")
    speed = (f"{rate:.0f} steps/s ({metrics['time/train_vs_bare']:.0%} of the bare env's "
             f"{metrics['time/bare_env_steps_per_s']:.0f})" if rate and metrics.get("time/train_vs_bare") is not None
             else "no steps taken now (policy re-exported)")
    console.print(
        f"train-ppo: {metrics['timesteps']} steps, success {metrics.get('episode/success_rate', 0):.0%} "
        f"(last 20 episodes), {speed}{chosen}"
    )


@app.command()
def evaluate(
    params: ParamsOpt = Path("params.yaml"),
    set_: SetOpt = None,
    terrain: Annotated[
        list[str] | None, typer.Option("--terrain", help="extra terrain name or YAML file (repeatable)")
    ] = None,
    write_page: Annotated[
        bool, typer.Option("--summary/--no-summary", help="also rewrite reports/README.md (off for side experiments)")
    ] = True,
) -> None:
    """Run the policy and baselines on the terrain suite; writes reports/eval (metrics, report, figures, videos)."""
    from hexpipe.evaluation.run import evaluate as run_evaluate
    from hexpipe.summary import write_summary

    cfg = load(params, set_)
    writable(cfg.eval.out_dir, cfg.eval.report_dir, *(["reports"] if write_page else []))
    with user_errors():
        summary_text = run_evaluate(cfg, extra_terrains=tuple(terrain or ()))
    console.print(summary_text)
    if write_page:
        console.print(f"wrote {write_summary(cfg, Path('reports/collect.json'), Path('reports/README.md'))}")


@app.command()
def play(
    params: ParamsOpt = Path("params.yaml"),
    set_: SetOpt = None,
    terrain: Annotated[str, typer.Option(help="scenario name or terrain YAML file")] = "single_block",
    seed: Annotated[int | None, typer.Option(help="seed of the first episode (default eval.seed)")] = None,
    episodes: Annotated[int, typer.Option(min=1, help="episodes, seeds seed, seed+1, ...")] = 1,
    policy: Annotated[str | None, typer.Option(help="trained policy folder (default eval.policy_dir)")] = None,
    blind: Annotated[str | None, typer.Option(help="a blind policy folder (ppo.blind=true) instead")] = None,
    gait: Annotated[str | None, typer.Option(help="a fixed gait a,b,omega (rad, rad, rad/s) instead")] = None,
    mcap: Annotated[Path | None, typer.Option(help="log the episode to this MCAP file (Foxglove)")] = None,
    video: Annotated[Path | None, typer.Option(help="film it: .mp4 (H.264) or .webm (VP9)")] = None,
    live: Annotated[bool, typer.Option("--live", help="stream it to Foxglove over WebSocket")] = False,
    host: Annotated[str, typer.Option(help="--live: address to bind (other than loopback exposes it)")] = "127.0.0.1",
    port: Annotated[int, typer.Option(min=0, max=65535, help="--live: port (0: any free one)")] = 8765,
    speed: Annotated[float, typer.Option(help="--live: sim seconds per wall second (1 = real time)")] = 1.0,
    wait: Annotated[bool, typer.Option(help="--live: start once a viewer has connected")] = True,
) -> None:
    """Watch one controller on one terrain: a summary, and optionally MCAP, a video, or a live Foxglove view."""
    from hexpipe.play import LiveOptions, controller_spec, describe, summary_lines
    from hexpipe.play import play as run_play

    cfg = load(params, set_)
    first = cfg.eval.seed if seed is None else seed
    with user_errors():
        spec = controller_spec(cfg, policy, blind, gait)
        options = LiveOptions(host=host, port=port, speed=speed, wait=wait) if live else None
        console.print(f"play: {describe(spec)} on {terrain}, seed {first}"
                      + (f" (+{episodes - 1} more)" if episodes > 1 else ""), highlight=False, soft_wrap=True)
        try:
            rows = run_play(cfg, spec, terrain, first, episodes, mcap=mcap, video=video, live=options,
                            echo=lambda text: console.print(text, highlight=False, markup=False, soft_wrap=True))
        except KeyboardInterrupt:
            console.print("stopped (Ctrl-C): the live server, if any, is down; unfinished MCAP and video files "
                          "were removed")
            raise typer.Exit(130) from None
    for line in summary_lines(rows):  # the summary goes to stdout
        typer.echo(line)
    for path in (mcap, video):
        if path is not None:
            shown = path if episodes == 1 else path.with_name(f"{path.stem}_0..{episodes - 1}{path.suffix}")
            typer.echo(f"wrote {shown}")


@app.command()
def summary(
    params: ParamsOpt = Path("params.yaml"),
    set_: SetOpt = None,
    collect_report: Annotated[Path, typer.Option(help="collect's JSON report")] = Path("reports/collect.json"),
    out: Annotated[Path, typer.Option(help="the markdown page")] = Path("reports/README.md"),
) -> None:
    """Write reports/README.md: one page linking every stage's figures and tables."""
    from hexpipe.summary import write_summary

    cfg = load(params, set_)
    console.print(f"wrote {write_summary(cfg, collect_report, out)}")


@app.command()
def bench(
    params: ParamsOpt = Path("params.yaml"),
    set_: SetOpt = None,
    terrains: Annotated[str, typer.Option(help="comma-separated terrains")] = "single_block,rough",
    windows: Annotated[int, typer.Option(min=1)] = 7,
    steps: Annotated[int, typer.Option(min=1, help="env steps per timed window")] = 60,
    train_steps: Annotated[int, typer.Option(min=0, help="PPO timesteps for the training rate (0: skip)")] = 3072,
    out: Annotated[Path, typer.Option(help="JSON report")] = Path("reports/bench/env.json"),
) -> None:
    """Env steps/s on one core (default config vs the pre-issue-12 physics; physics only, + height map, + camera)
    and PPO training steps/s against the bare env rate; writes a JSON report."""
    from hexpipe.bench import bench_env, bench_training

    cfg = load(params, set_)
    with user_errors():
        result = bench_env(cfg, tuple(t for t in terrains.split(",") if t), windows=windows, steps=steps)
        if train_steps:
            result["training"] = bench_training(cfg, train_steps)
    write_json(out, result)
    for terrain, row in result.items():
        if not isinstance(row, dict) or "physics" not in row:
            continue
        console.print(
            f"{terrain:13s} default config {row['default']['steps_per_s']:6.0f} steps/s | baseline physics "
            f"{row['baseline']['steps_per_s']:6.0f} | speedup {row['speedup_vs_baseline']:.2f}x"
        )
        console.print(
            f"{terrain:13s} physics {row['physics']['steps_per_s']:6.0f} steps/s | "
            f"+heightmap {row['heightmap']['steps_per_s']:6.0f} "
            f"({100 * row['heightmap']['overhead_vs_physics']:+.1f}%, "
            f"read {row['heightmap_read_ms']:.3f} ms = {100 * row['heightmap_read_vs_physics_step']:.1f}% of a step) | "
            f"+camera {row['camera']['steps_per_s']:6.0f} (read {row['camera_read_ms']:.2f} ms)"
        )
    if "training" in result:
        t = result["training"]
        console.print(
            f"PPO, {t['n_envs']} envs: {t['train_steps_per_s']:.0f} steps/s, {t['train_vs_bare']:.0%} of the bare "
            f"env's {t['bare_env_steps_per_s']:.0f} steps/s in the same run ({t['rollout_forward']} rollout forward, "
            f"medians of {t['rounds']} runs); torch forward {t['forwards']['torch']['train_vs_bare']:.0%}, numpy "
            f"forward {t['forwards']['numpy']['train_vs_bare']:.0%} ({t['numpy_vs_torch_forward']:.2f}x the rate)"
        )
    console.print(f"wrote {out}")


@app.command()
def sweep(
    params: ParamsOpt = Path("params.yaml"),
    set_: SetOpt = None,
    name: Annotated[str | None, typer.Option(help="sweep name (sweep.name): the output folders")] = None,
    seeds: Annotated[str | None, typer.Option(help="comma-separated training seeds (sweep.seeds)")] = None,
    condition: Annotated[list[str] | None, typer.Option(
        "--condition", help="NAME:section.key=value;section.key=value (repeatable; replaces sweep.conditions)")] = None,
    compare: Annotated[list[str] | None, typer.Option(
        "--compare", help="A,B: report P(A beats B) (repeatable; replaces sweep.compare)")] = None,
    cpus: Annotated[int | None, typer.Option(min=0, help="CPUs of the local Ray cluster (0 = all)")] = None,
    address: Annotated[str | None, typer.Option(
        help="join this Ray cluster (host:port or 'auto'; default $RAY_ADDRESS, else start a local one)")] = None,
    train_encoder: Annotated[bool | None, typer.Option(
        "--train-encoder/--pipeline-encoder",
        help="each trial trains its own encoder with vae.seed = its seed (sweep.train_encoder), or all load "
             "ppo.encoder_dir")] = None,
    dry_run: Annotated[bool, typer.Option("--dry-run", help="list the trials and exit")] = False,
) -> None:
    """Train and evaluate every condition x seed of the `sweep:` params on Ray; report success with intervals."""
    import json
    import shlex
    import sys

    from hexpipe.config import apply_overrides
    from hexpipe.sweep.grid import expand, parse_condition
    from hexpipe.sweep.run import run_sweep

    cfg = load(params, set_)
    extra = [f"sweep.name={name}"] if name is not None else []
    with user_errors():
        if seeds is not None:
            extra.append(f"sweep.seeds=[{seeds}]")
        if condition:
            extra.append(f"sweep.conditions={json.dumps(dict(parse_condition(c) for c in condition))}")
        if compare:
            extra.append(f"sweep.compare={json.dumps([c.split(',') for c in compare])}")
        if train_encoder is not None:
            extra.append(f"sweep.train_encoder={str(train_encoder).lower()}")
        cfg = apply_overrides(cfg, extra, source="hexpipe sweep") if extra else cfg
        if dry_run:
            for trial in expand(cfg):
                encoder = f"; trains encoder {trial.encoder}" if trial.encoder else ""
                console.print(f"{trial.name}: {' '.join(trial.overrides) or '(no overrides)'}{encoder}; "
                              f"{trial.cpus} CPUs", highlight=False, markup=False)
            return
        try:
            outcome, out_dir = run_sweep(cfg, shlex.join(["hexpipe", *sys.argv[1:]]), address=address, cpus=cpus,
                                         log=lambda text: console.print(text, highlight=False, markup=False))
        except ConnectionError as exc:
            raise ConfigError(f"cannot reach the Ray cluster at {address or 'RAY_ADDRESS'}: {exc}") from None
    console.print(f"sweep: {len(outcome.results)} trials complete ({len(outcome.ran)} run now, "
                  f"{len(outcome.skipped)} kept), {len(outcome.failures)} failed; report: {out_dir / 'report.md'}")
    if outcome.failures:
        raise typer.Exit(1)


if __name__ == "__main__":  # python -m hexpipe.cli
    app()
