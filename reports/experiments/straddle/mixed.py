"""The `mixed` validation set of `straddle_select`: what train-ppo would score with validation episodes drawn from
[varied_open, two_blocks] in turn (episode i on terrain i % 2, seed 5000 + i), read from episodes already run.

    .venv/bin/python reports/experiments/straddle/mixed.py TWO_BLOCKS.csv OUT.csv

TWO_BLOCKS.csv is validate.py's run of `two_blocks.yaml` (seeds 5000..). Each of its trials' own varied_open
episodes are train-ppo's, in TRIAL/ppo/validation.json (the same seeds and sum; validate.py agrees to the last
digit). Writes OUT.csv (trial, seed, terrain, success, env_return: the odd seeds from two_blocks, the even from
varied_open) and prints, per trial, the mean return and success on each set.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pandas as pd


def own_rows(trial: str) -> pd.DataFrame:
    path = Path(trial) / "ppo" / "validation.json"
    if not path.is_file():
        raise SystemExit(f"error: {path}: not found (a trial trained with validation episodes holds it)")
    rows = pd.DataFrame(json.loads(path.read_text())["rows"]).rename(columns={"return": "env_return"})
    return rows.assign(trial=trial)[["trial", "seed", "terrain", "success", "env_return"]]


def main(two_blocks_csv: Path, out: Path) -> None:
    two = pd.read_csv(two_blocks_csv).assign(terrain="two_blocks")[["trial", "seed", "terrain", "success",
                                                                   "env_return"]]
    own = pd.concat([own_rows(t) for t in two["trial"].unique()])
    if set(own["terrain"]) != {"varied_open"}:
        raise SystemExit(f"error: the trials' own validation sets are {sorted(set(own['terrain']))}, not varied_open")
    mixed = pd.concat([own[own["seed"] % 2 == 0], two[two["seed"] % 2 == 1]]).sort_values(["trial", "seed"])
    tmp = out.with_suffix(".tmp")
    mixed.to_csv(tmp, index=False)
    tmp.replace(out)
    table = pd.concat({name: g.groupby("trial")[["env_return", "success"]].mean()
                       for name, g in (("varied_open", own), ("two_blocks", two), ("mixed", mixed))}, axis=1)
    pd.set_option("display.width", 200)
    print(table.round(3).to_string())


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    main(Path(sys.argv[1]), Path(sys.argv[2]))
