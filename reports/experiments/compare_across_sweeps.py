"""P(a beats b) over training seeds, as a sweep report computes it (hexpipe.sweep.tables.improvements), for conditions
whose trials ran in different sweeps: each side pools the records of one or more SWEEP_FOLDER:CONDITION.

    .venv/bin/python reports/experiments/compare_across_sweeps.py \
        --a reports/sweeps/levers:default --a reports/sweeps/forward:numpy \
        --b reports/sweeps/privileged:default --b reports/sweeps/forward:torch

--stalls adds the failed episodes on the block courses, counted by where the feet were when each ended;
--terrains adds each terrain's success, the mean over seeds of each seed's rate.
--seeds 0,1,2,3 keeps only those training seeds on both sides (a paired comparison with a longer sweep).
--paired adds the suite success of a minus b, seed by seed on the seeds both sides hold, with a bootstrap interval
over whole seeds (the same draw of encoder and PPO seed on both sides, where the sweeps trained their encoders), and
the same paired difference of flat ground's cost of transport and of the adaptation (b before the single block's
face minus b on its open ground, rad);
--targets adds issue 10's targets judged on each side, as a sweep report judges them.
"""

import argparse
import json
from pathlib import Path

from hexpipe.sweep.stats import bootstrap_mean
from hexpipe.sweep.tables import (
    LEARNED,
    adaptation_per_seed,
    episodes_frame,
    improvements,
    judge_targets,
    per_seed,
    target_parts,
)

BLOCK_COURSES = ("single_block", "extra_blocks", "wide_block", "tall_block", "block_near", "block_far")
# stall_legs "none": stuck or fallen with no foot at a block face (on or past a block); "-": the episode ran out
# of time (no stall recorded); anything else names the legs with a foot at a face
STALL_KIND = {"none": "no foot at a face", "-": "time limit", "": "time limit"}


def records(sources: list[str], name: str, keep: set[int] | None = None) -> list[dict]:
    """Every trial record of the sources, as condition `name`; a training seed found in two sources is an error
    (the per-seed statistics would merge the two policies into one seed)."""
    out, seen = [], {}
    for source in sources:
        folder, _, condition = source.rpartition(":")
        for path in sorted(Path(folder).glob(f"{condition}-seed*/result.json")):
            record = json.loads(path.read_text())
            if keep is not None and record["seed"] not in keep:
                continue
            if record["seed"] in seen:
                raise SystemExit(f"error: seed {record['seed']} is in both {seen[record['seed']]} and {source}")
            seen[record["seed"]] = source
            out.append({**record, "condition": name})
    if not out:
        raise SystemExit(f"error: no trial records in {', '.join(sources)} "
                         "(SWEEP_FOLDER:CONDITION reads SWEEP_FOLDER/CONDITION-seedN/result.json)")
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--a", action="append", required=True, help="SWEEP_FOLDER:CONDITION (repeatable)")
    parser.add_argument("--b", action="append", required=True, help="SWEEP_FOLDER:CONDITION (repeatable)")
    parser.add_argument("--stalls", action="store_true", help="also count the failed episodes on the block courses "
                        "by where the feet were (evaluate's stall_legs)")
    parser.add_argument("--terrains", action="store_true", help="also print each terrain's success per side (mean "
                        "over seeds of each seed's success rate)")
    parser.add_argument("--paired", action="store_true", help="also print the suite success of a minus b on the "
                        "seeds both hold, with a bootstrap interval over whole seeds")
    parser.add_argument("--targets", action="store_true", help="also judge issue 10's targets on each side")
    parser.add_argument("--seeds", help="comma-separated training seeds to keep on both sides (default: all)")
    args = parser.parse_args()
    keep = None if args.seeds is None else {int(s) for s in args.seeds.split(",")}
    everything = episodes_frame(records(args.a, "a", keep) + records(args.b, "b", keep))
    episodes = everything[everything["controller"] == LEARNED]
    terrains = list(dict.fromkeys(episodes["terrain"]))
    result = improvements(per_seed(episodes), [("a", "b")], terrains)["a_vs_b"]["all"]
    pooled = episodes.groupby("condition")["success"].mean()
    seeds = episodes.groupby("condition")["trial"].nunique()
    nan = float("nan")  # one seed on a side: the bootstrap gives no interval
    print(f"P(a beats b) = {result.get('probability', nan):.2f} [{result.get('probability_low', nan):.2f}, "
          f"{result.get('probability_high', nan):.2f}]; pooled success a {pooled['a']:.2f} ({seeds['a']} seeds), "
          f"b {pooled['b']:.2f} ({seeds['b']} seeds)")
    if args.terrains:
        rates = episodes.groupby(["condition", "terrain", "trial"])["success"].mean()
        table = rates.groupby(["terrain", "condition"]).mean().unstack().reindex(terrains)
        print("success per terrain (mean over seeds):")
        print(table.round(2).to_string())
    if args.paired:
        table = per_seed(episodes)
        seeds_of = table.pivot_table(index=["terrain", "train_seed"], columns="condition", values="success").dropna()
        if not {"a", "b"} <= set(seeds_of.columns) or seeds_of.empty:
            print("suite success a - b: no training seed on both sides (see --seeds)")
        else:
            gap = (seeds_of["a"] - seeds_of["b"]).unstack("train_seed").reindex(terrains)
            estimate = bootstrap_mean(list(gap.to_numpy()))
            per = gap.mean(axis=0)
            print(f"suite success a - b, paired on {gap.shape[1]} seeds: {estimate.value:+.3f} "
                  f"[{estimate.low:+.3f}, {estimate.high:+.3f}]; a ahead on {(per > 0).sum()} seeds, "
                  f"behind on {(per < 0).sum()}")
        flat = table[table["terrain"] == "flat"]
        for label, frame, column in (("flat cost of transport", flat, "cost_of_transport"),
                                     ("adaptation (rad)", adaptation_per_seed(episodes), "adaptation")):
            both = frame.pivot_table(index="train_seed", columns="condition", values=column).dropna()
            if not {"a", "b"} <= set(both.columns) or both.empty:
                print(f"{label} a - b: not measured on a training seed of both sides")
                continue
            diff = bootstrap_mean([(both["a"] - both["b"]).to_numpy(float)])
            print(f"{label} a - b, paired on {len(both)} seeds: {diff.value:+.3f} [{diff.low:+.3f}, {diff.high:+.3f}]")
    if args.targets:
        judged = judge_targets(target_parts(everything, ["a", "b"], "flat"), ["a", "b"], "flat")
        judged["value"] = judged.apply(lambda r: f"{r['value']:+.2f} [{r['low']:+.2f}, {r['high']:+.2f}]"
                                       + (" met" if r["met"] else ""), axis=1)
        print("issue 10's targets (worst terrain's value over seeds):")
        print(judged.pivot(index="target", columns="condition", values="value")
              .reindex(judged["target"].unique()).to_string())
        print("met:", ", ".join(f"{c} {int(judged[judged['condition'] == c]['met'].sum())} of "
                                f"{int((judged['condition'] == c).sum())}" for c in ("a", "b")))
    if args.stalls:
        failed = episodes[~episodes["success"] & episodes["terrain"].isin(BLOCK_COURSES)]
        where = failed["stall_legs"].fillna("-").map(lambda legs: STALL_KIND.get(legs, "a foot at a face"))
        table = failed.groupby([failed["condition"], where]).size().unstack(fill_value=0)
        print(f"failed episodes on {', '.join(BLOCK_COURSES)}, by where the feet were:")
        print(table.to_string())


if __name__ == "__main__":
    main()
