"""Per terrain, how many of a condition's trials beat their fixed gait (evaluate's verdict: success within 5
points, no slower and cheaper), and the mean over trials of the policy minus the fixed gait in success, time to
goal (s) and cost of transport (those two over the trials with successes on both sides); then each trial's count
of terrains beaten (`verdict/policy/terrains_beaten`). The last columns are the policy's own mean a, b (rad) and
omega (rad/s) on each terrain, for the fixed gait's a 0.4, b 0.4, omega pi.

    .venv/bin/python reports/experiments/open/verdict_terrains.py reports/sweeps/open open_teacher
"""

import json
import sys
from pathlib import Path

import pandas as pd


def _mean(stats: dict, key: str) -> float:
    """A mean over the episodes that reached the goal; NaN (left out of the means) where none did."""
    value = stats.get(key)
    return float("nan") if value is None else float(value)


sweep, condition = Path(sys.argv[1]), sys.argv[2]
rows, trials = [], []
for path in sorted(sweep.glob(f"{condition}-seed*/eval/metrics.json")):
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
