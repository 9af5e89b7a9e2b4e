"""How high each policy lifts before a block's first face, episode by episode, and whether the episode crossed.

For every trial of one condition of a sweep: the highest b (rad) the policy's CPG reached while the base was
between 0.2 and 0.5 m from the start, the approach in which the front feet meet a first face at 1.0 m (the single,
wide, tall and low blocks and extra blocks; an episode that fails there stalls with the base at 0.45-0.50 m; the
window does not fit block_near or block_far), on each episode of the named terrains, beside that episode's
success. The sweep's own `b_before_block` cannot say this: it is empty for an episode that stalls at the face,
which are the episodes in question. It reads each trial's evaluation traces
(`<data>/sweeps/NAME/TRIAL/eval/cpg_traces.csv.gz`, not committed) and the sweep's `episodes.csv`.

    .venv/bin/python reports/experiments/stride_track/face_lift.py reports/sweeps/stride_track pinned_stride60

`--at-face` reads instead the lowest b with the base 0.40-0.50 m from the start, as the front feet (0.47 m ahead of
the base) reach a face at 1.0 m: a lift raised early and let fall before the face shows a high first table and a
low second one.
"""

import argparse
import sys
from pathlib import Path

import pandas as pd

WINDOW = (0.2, 0.5)  # m of base travel: the approach to a face at the suite's default block position
AT_FACE = (0.4, 0.5)  # m of base travel: the front feet reach a face at 1.0 m


def face_lift(traces: pd.DataFrame, terrains: list[str], window: tuple[float, float] = WINDOW,
              stat: str = "max") -> pd.Series:
    """The policy's highest (stat "max") or lowest ("min") b in `window`, per (terrain, episode)."""
    t = traces[(traces.controller == "policy") & traces.terrain.isin(terrains)]
    t = t[(t.distance > window[0]) & (t.distance < window[1])]
    return t.groupby(["terrain", "episode"]).b.agg(stat)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sweep", type=Path, help="the sweep's report folder, e.g. reports/sweeps/stride_track")
    ap.add_argument("condition")
    ap.add_argument("--data", type=Path, default=Path("data/sweeps"), help="where the sweeps' trial data live")
    ap.add_argument("--terrain", action="append", help="terrains to read (default: single_block, wide_block)")
    ap.add_argument("--at-face", action="store_true", help="the lowest b with the base 0.40-0.50 m from the start")
    args = ap.parse_args()
    window, stat, word = (AT_FACE, "min", "lowest") if args.at_face else (WINDOW, "max", "highest")
    terrains = args.terrain or ["single_block", "wide_block"]
    episodes_csv = args.sweep / "episodes.csv"
    if not episodes_csv.is_file():
        sys.exit(f"error: {episodes_csv} not found: run the sweep (or its report) first")
    episodes = pd.read_csv(episodes_csv)
    episodes = episodes[(episodes.condition == args.condition) & (episodes.controller == "policy")]
    if episodes.empty:
        sys.exit(f"error: no policy episodes of condition {args.condition!r} in {episodes_csv}")
    unknown = sorted(set(terrains) - set(episodes.terrain))
    if unknown:
        sys.exit(f"error: --terrain {', '.join(unknown)}: no such terrain in {episodes_csv} "
                 f"(it has {', '.join(sorted(episodes.terrain.unique()))})")
    for trial, rows in episodes.groupby("trial"):
        path = args.data / args.sweep.name / str(trial) / "eval" / "cpg_traces.csv.gz"
        if not path.is_file():
            sys.exit(f"error: {path} not found: the traces are not committed; rerun the sweep's trial to make them")
        lift = face_lift(pd.read_csv(path), terrains, window, stat).rename("b")
        crossed = rows.set_index(["terrain", "episode"]).success.astype(bool).rename("crossed")
        table = pd.concat([lift, crossed], axis=1, join="inner")
        print(f"{trial}: {word} b with the base {window[0]}-{window[1]} m from the start, and crossed (+) or not (-)")
        cells = table.apply(lambda r: f"{r.b:.2f}{'+' if r.crossed else '-'}", axis=1).unstack("episode")
        print(cells.to_string(), end="\n\n")


if __name__ == "__main__":
    main()
