"""Per terrain, how many of a condition's trials beat their fixed gait (evaluate's verdict: success within 5
points, no slower and cheaper), and the mean over trials of the policy minus the fixed gait in success, time to
goal (s) and cost of transport (those two over the trials with successes on both sides); then each trial's count
of terrains beaten (`verdict/policy/terrains_beaten`). The last columns are the policy's own mean a, b (rad) and
omega (rad/s) on each terrain, for the fixed gait's a 0.4, b 0.4, omega pi.

With `--against SWEEP_FOLDER:CONDITION`, it then pairs the two by training seed: each seed's count of terrains
beaten on both sides, the mean of this condition minus the other with its 95% bootstrap interval over whole seeds,
and per terrain how many of the shared seeds beat the fixed gait on each side.

    .venv/bin/python reports/experiments/open/verdict_terrains.py reports/sweeps/open open_teacher
    .venv/bin/python reports/experiments/open/verdict_terrains.py reports/sweeps/pinned pinned \
        --against reports/sweeps/open:open_teacher [--seeds 1,1001,2001]

--seeds keeps only those training seeds' trials, so a figure read on a sweep's first seeds still reprints after
more seeds were added to it.
"""

import argparse
import json
from pathlib import Path

import pandas as pd

from hexpipe.sweep.stats import bootstrap_mean

SUMMARIES = ("beats_best_fixed_everywhere", "terrains_beaten", "terrains")  # verdict keys that are not a terrain


def _mean(stats: dict, key: str) -> float:
    """A mean over the episodes that reached the goal; NaN (left out of the means) where none did."""
    value = stats.get(key)
    return float("nan") if value is None else float(value)


def _seed(path: Path) -> int:
    """The training seed of a trial's <sweep>/<condition>-seed<N>/eval/metrics.json."""
    return int(path.parent.parent.name.rsplit("-seed", 1)[1])


def _trials(sweep: Path, condition: str, seeds: set[int] | None = None) -> list[Path]:
    paths = sorted(sweep.glob(f"{condition}-seed*/eval/metrics.json"))
    paths = [p for p in paths if seeds is None or _seed(p) in seeds]
    if not paths:
        raise SystemExit(f"error: {sweep}: no trial of {condition!r} has eval/metrics.json"
                         + (f" among seeds {sorted(seeds)}" if seeds else ""))
    return paths


def terrain_table(sweep: Path, condition: str, seeds: set[int] | None = None) -> None:
    """Print the per-terrain differences from the fixed gait and each trial's count of terrains beaten."""
    rows, trials = [], []
    for path in _trials(sweep, condition, seeds):
        metrics = json.loads(path.read_text())
        for terrain in [k for k, v in metrics.items() if isinstance(v, dict) and "policy" in v]:
            policy, fixed = metrics[terrain]["policy"], metrics[terrain]["best_fixed"]
            trials.append(path.parent.parent.name)
            rows.append(
                {
                    "terrain": terrain,
                    "beaten": metrics[f"verdict/policy/{terrain}"],
                    "success": policy["success_rate"] - fixed["success_rate"],
                    "time (s)": _mean(policy, "time_to_goal_mean") - _mean(fixed, "time_to_goal_mean"),
                    "cost of transport": _mean(policy, "cost_of_transport") - _mean(fixed, "cost_of_transport"),
                    **{f"policy {k}": policy[f"{k}_mean"] for k in ("a", "b", "omega")},
                }
            )
    table = (
        pd.DataFrame(rows)
        .groupby("terrain", sort=False)
        .agg(
            beaten=("beaten", "sum"),
            trials=("beaten", "size"),
            success=("success", "mean"),
            time=("time (s)", "mean"),
            cost_of_transport=("cost of transport", "mean"),
            a=("policy a", "mean"),
            b=("policy b", "mean"),
            omega=("policy omega", "mean"),
        )
    )
    print(f"{condition} minus its fixed gait, mean over trials ({sweep})")
    signed, plain = "{:+.2f}".format, "{:.2f}".format  # differences from the fixed gait; the policy's own a, b, omega
    formats = {c: plain if c in ("a", "b", "omega") else signed for c in table.columns if c not in ("beaten", "trials")}
    print(table.to_string(formatters=formats))
    beaten = pd.DataFrame(rows).assign(trial=trials).groupby("trial", sort=False)["beaten"].sum()
    print("terrains beaten per trial: " + ", ".join(f"{trial} {count}" for trial, count in beaten.items()))


def verdicts(sweep: Path, condition: str, seeds: set[int] | None = None) -> pd.DataFrame:
    """One row per training seed, one column per terrain (1: beaten), from each trial's eval/metrics.json."""
    rows = {}
    for path in _trials(sweep, condition, seeds):
        metrics = json.loads(path.read_text())
        rows[_seed(path)] = {
            k.removeprefix("verdict/policy/"): v
            for k, v in metrics.items()
            if k.startswith("verdict/policy/") and k.count("/") == 2 and k.rsplit("/", 1)[1] not in SUMMARIES
        }
    return pd.DataFrame.from_dict(rows, orient="index").sort_index()


def paired(a_name: str, a: pd.DataFrame, b_name: str, b: pd.DataFrame) -> None:
    """Print terrains beaten per shared seed, a minus b with its bootstrap interval, and seeds beating per terrain."""
    seeds = a.index.intersection(b.index)
    if seeds.empty:
        raise SystemExit(f"error: {a_name} and {b_name} share no training seed")
    beaten = pd.DataFrame({a_name: a.loc[seeds].sum(axis=1), b_name: b.loc[seeds].sum(axis=1)})
    print(f"\nterrains beaten of {a.shape[1]}, per training seed")
    print(beaten.to_string())
    diff = bootstrap_mean([(beaten[a_name] - beaten[b_name]).to_numpy(float)])
    print(
        f"mean {beaten[a_name].mean():.2f} against {beaten[b_name].mean():.2f}; paired a - b {diff.value:+.2f} "
        f"[{diff.low:+.2f}, {diff.high:+.2f}] over {len(seeds)} seeds"
    )
    print("\nseeds that beat the fixed gait, per terrain")
    print(pd.DataFrame({a_name: a.loc[seeds].sum(), b_name: b.loc[seeds].sum()}).to_string())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("sweep", type=Path, help="a sweep's report folder, e.g. reports/sweeps/open")
    ap.add_argument("condition")
    ap.add_argument("--against", metavar="SWEEP_FOLDER:CONDITION", help="pair with this condition by training seed")
    ap.add_argument("--seeds", help="only these training seeds, comma-separated (default: every trial)")
    args = ap.parse_args()
    try:
        seeds = {int(s) for s in args.seeds.split(",")} if args.seeds else None
    except ValueError:
        raise SystemExit(f"error: --seeds {args.seeds!r} is not comma-separated whole numbers") from None
    terrain_table(args.sweep, args.condition, seeds)
    if args.against:
        if ":" not in args.against:
            raise SystemExit(f"error: --against {args.against!r} is not SWEEP_FOLDER:CONDITION")
        folder, other = args.against.rsplit(":", 1)
        this = f"{args.sweep}:{args.condition}"
        paired(this, verdicts(args.sweep, args.condition, seeds), args.against, verdicts(Path(folder), other, seeds))


if __name__ == "__main__":
    main()
