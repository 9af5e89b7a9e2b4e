"""Terrains where each trial beats its fixed gait (evaluate's verdict: success within 5 points, no slower and
cheaper; `verdict/policy/terrains_beaten`), for two SWEEP_FOLDER:CONDITION sides paired by training seed, with the
mean of a minus b and its 95% bootstrap interval over whole seeds; then, per terrain, how many seeds beat it.

    .venv/bin/python reports/experiments/pinned/beaten_paired.py reports/sweeps/pinned:pinned \
        reports/sweeps/open:open_teacher
"""

import json
import sys
from pathlib import Path

import pandas as pd

from hexpipe.sweep.stats import bootstrap_mean


def verdicts(side: str) -> pd.DataFrame:
    """One row per seed, one column per terrain (1: beaten), from each trial's eval/metrics.json."""
    folder, condition = side.rsplit(":", 1)
    rows = {}
    for path in sorted(Path(folder).glob(f"{condition}-seed*/eval/metrics.json")):
        metrics = json.loads(path.read_text())
        seed = int(path.parent.parent.name.rsplit("-seed", 1)[1])
        rows[seed] = {k.removeprefix("verdict/policy/"): v for k, v in metrics.items()
                      if k.startswith("verdict/policy/") and k.count("/") == 2
                      and k.rsplit("/", 1)[1] not in ("beats_best_fixed_everywhere", "terrains_beaten", "terrains")}
    if not rows:
        raise SystemExit(f"{side}: no trial has eval/metrics.json")
    return pd.DataFrame.from_dict(rows, orient="index").sort_index()


a_side, b_side = sys.argv[1], sys.argv[2]
a, b = verdicts(a_side), verdicts(b_side)
seeds = a.index.intersection(b.index)
beaten = pd.DataFrame({a_side: a.loc[seeds].sum(axis=1), b_side: b.loc[seeds].sum(axis=1)})
print(f"terrains beaten of {a.shape[1]}, per training seed")
print(beaten.to_string())
diff = bootstrap_mean([(beaten[a_side] - beaten[b_side]).to_numpy(float)])
print(f"mean {beaten[a_side].mean():.2f} against {beaten[b_side].mean():.2f}; paired a - b {diff.value:+.2f} "
      f"[{diff.low:+.2f}, {diff.high:+.2f}] over {len(seeds)} seeds")
print("\nseeds that beat the fixed gait, per terrain")
print(pd.DataFrame({a_side: a.loc[seeds].sum(), b_side: b.loc[seeds].sum()}).to_string())
