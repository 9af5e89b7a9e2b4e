"""What the heading reflex changes, from a heading.py CSV: time to goal (s) and cost of transport, gain B minus
gain A, over the episodes both gains finish, per terrain, per controller and over all; then successes and the
episodes that turned more than 0.5 rad at some step, per gain.

    .venv/bin/python reports/experiments/heading/changes.py reports/experiments/heading/policies.csv [--a 0 --b 1]
"""

from __future__ import annotations

import argparse

import pandas as pd

KEY = ["controller", "terrain", "episode"]
TURNED = 0.5  # rad, as heading.py


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("--a", type=float, default=0.0)
    ap.add_argument("--b", type=float, default=1.0)
    a = ap.parse_args()
    try:
        frame = pd.read_csv(a.csv)
    except (OSError, ValueError) as exc:
        raise SystemExit(f"error: {a.csv}: {exc}") from None
    if not {a.a, a.b} <= set(frame.gain):
        raise SystemExit(f"error: {a.csv} has gains {sorted(set(frame.gain))}, not both {a.a:g} and {a.b:g}")
    both = frame.pivot_table(index=KEY, columns="gain", values="success").all(axis=1)
    change = pd.DataFrame({
        name: (table[a.b] - table[a.a])[both]
        for name, table in ((col, frame.pivot_table(index=KEY, columns="gain", values=col))
                            for col in ("time", "cost_of_transport"))})
    print(f"gain {a.b:g} minus gain {a.a:g}, over the {len(change)} episodes both finish (mean)")
    print(change.groupby(level="terrain").mean().round(3).T.to_string())
    print()
    print(change.groupby(level="controller").mean().round(3).to_string())
    print(f"\nall: time {change.time.mean():+.3f} s, cost of transport {change.cost_of_transport.mean():+.3f}")
    per_gain = frame.groupby("gain").agg(success=("success", "sum"), episodes=("success", "size"),
                                         turned=("max_abs_yaw", lambda s: int((s > TURNED).sum())))
    print(per_gain.to_string())


if __name__ == "__main__":
    main()
