"""One markdown row per training seed of a lift-price condition, beside the same seed of reference conditions
(default: `ramp10` of the `lift_ramp` sweep and `old_default`, the default before the lift price: `encoder_draw`,
seed 6 from `draw678`): the per-seed tables of the lift_zone_* and zone_* sections of reports/experiments.

    .venv/bin/python reports/experiments/lift_zone/seed_table.py lift_zone_feet feet10 0,1,2,3,4,5,6
    .venv/bin/python reports/experiments/lift_zone/seed_table.py lift_zone_price feet30 0,1,2,3,4,5,6 \
        lift_zone_feet:feet10 old_default

Columns: success over the suite but flat ground; success on the single, extra, wide and tall block; b in the 0.3 m
before the single block's face / on its open ground (rad, the lift in brackets, bold at the 0.15 target); on flat
ground the mean b, the cost of transport and the time to goal of the episodes that arrived; then the suite, lift
and flat b of each reference. Reads each trial's eval/results.csv under reports/sweeps/.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

SWEEPS = Path("reports/sweeps")


def summary(trial: Path) -> dict:
    """The figures of one trial's learned policy (evaluate's results.csv); a missing trial is refused by name."""
    path = trial / "eval" / "results.csv"
    if not path.exists():
        raise SystemExit(f"error: {path}: no such file (has that seed run?)")
    results = pd.read_csv(path)
    policy = results[results["controller"] == "policy"]
    single = policy[policy["terrain"] == "single_block"]
    flat = policy[policy["terrain"] == "flat"]
    arrived = flat[flat["success"]]
    return {"suite": policy[policy["terrain"] != "flat"]["success"].mean(),
            "per": policy.groupby("terrain")["success"].mean(),
            "before": single["b_before_block"].mean(), "open": single["b_open"].mean(),
            "flat_b": flat["b_mean"].mean(), "cot": arrived["cost_of_transport"].mean(), "time": arrived["time"].mean()}


def reference(name: str, seed: int) -> str:
    """A reference's suite, lift and flat b for `seed`; `name` is SWEEP:CONDITION or old_default."""
    if name == "old_default":
        trial = SWEEPS / ("encoder_draw" if seed < 6 else "draw678") / f"default-seed{seed}"
    else:
        sweep, _, condition = name.partition(":")
        trial = SWEEPS / sweep / f"{condition}-seed{seed}"
    s = summary(trial)
    return f"{s['suite']:.2f}, {s['before'] - s['open']:+.2f}, flat b {s['flat_b']:.2f}"


def main() -> None:
    if len(sys.argv) < 4:
        raise SystemExit("usage: seed_table.py SWEEP CONDITION SEEDS [SWEEP:CONDITION | old_default ...]")
    sweep, condition = sys.argv[1], sys.argv[2]
    try:
        seeds = [int(s) for s in sys.argv[3].split(",")]
    except ValueError:
        raise SystemExit(f"error: SEEDS: expected comma-separated integers, got {sys.argv[3]!r}") from None
    references = sys.argv[4:] or ["lift_ramp:ramp10", "old_default"]
    for seed in seeds:
        s = summary(SWEEPS / sweep / f"{condition}-seed{seed}")
        lift = s["before"] - s["open"]
        shown = f"**{lift:+.2f}**" if lift >= 0.15 else f"{lift:+.2f}"
        blocks = " / ".join(f"{s['per'][t]:.1f}" for t in ("single_block", "extra_blocks", "wide_block", "tall_block"))
        print(f"| {seed} | {s['suite']:.2f} | {blocks} | {s['before']:.2f} / {s['open']:.2f} ({shown}) | "
              f"{s['flat_b']:.2f}, {s['cot']:.2f}, {s['time']:.1f} s | "
              + " | ".join(reference(name, seed) for name in references) + " |")


if __name__ == "__main__":
    main()
