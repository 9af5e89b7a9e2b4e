"""One markdown row per training seed of a lift-price condition, beside the same seed of `ramp10` (the `lift_ramp`
sweep) and of the old default (`encoder_draw`, seed 6 from `draw678`): the table of the lift_zone_feet section.

    .venv/bin/python reports/experiments/lift_zone/seed_table.py lift_zone_feet feet10 0,1,2,3,4,5,6

Columns: success over the suite but flat ground; success on the single, extra, wide and tall block; b in the 0.3 m
before the single block's face / on its open ground (rad, the lift in brackets, bold at the 0.15 target); on flat
ground the mean b, the cost of transport and the time to goal of the episodes that arrived; then the suite, lift
and flat b of the two references. Reads each trial's eval/results.csv under reports/sweeps/.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

SWEEPS = Path("reports/sweeps")


def summary(trial: Path) -> dict:
    """The figures of one trial's learned policy (evaluate's results.csv)."""
    results = pd.read_csv(trial / "eval" / "results.csv")
    policy = results[results["controller"] == "policy"]
    single = policy[policy["terrain"] == "single_block"]
    flat = policy[policy["terrain"] == "flat"]
    arrived = flat[flat["success"]]
    return {"suite": policy[policy["terrain"] != "flat"]["success"].mean(),
            "per": policy.groupby("terrain")["success"].mean(),
            "before": single["b_before_block"].mean(), "open": single["b_open"].mean(),
            "flat_b": flat["b_mean"].mean(), "cot": arrived["cost_of_transport"].mean(), "time": arrived["time"].mean()}


def reference(trial: Path) -> str:
    s = summary(trial)
    return f"{s['suite']:.2f}, {s['before'] - s['open']:+.2f}, flat b {s['flat_b']:.2f}"


def main() -> None:
    if len(sys.argv) != 4:
        raise SystemExit(__doc__.strip().splitlines()[2].strip())
    sweep, condition, seeds = sys.argv[1], sys.argv[2], [int(s) for s in sys.argv[3].split(",")]
    for seed in seeds:
        trial = SWEEPS / sweep / f"{condition}-seed{seed}"
        if not (trial / "eval" / "results.csv").exists():
            raise SystemExit(f"error: {trial}/eval/results.csv: no such file (has seed {seed} run?)")
        s = summary(trial)
        lift = s["before"] - s["open"]
        shown = f"**{lift:+.2f}**" if lift >= 0.15 else f"{lift:+.2f}"
        blocks = " / ".join(f"{s['per'][t]:.1f}" for t in ("single_block", "extra_blocks", "wide_block", "tall_block"))
        default = SWEEPS / ("encoder_draw" if seed < 6 else "draw678") / f"default-seed{seed}"
        print(f"| {seed} | {s['suite']:.2f} | {blocks} | {s['before']:.2f} / {s['open']:.2f} ({shown}) | "
              f"{s['flat_b']:.2f}, {s['cot']:.2f}, {s['time']:.1f} s | "
              f"{reference(SWEEPS / 'lift_ramp' / f'ramp10-seed{seed}')} | {reference(default)} |")


if __name__ == "__main__":
    main()
