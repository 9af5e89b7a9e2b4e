"""Would a stronger elevator have freed the trained policies' hind feet at a face? Evaluate's episodes of the given
terrains, replayed for every complete trial of a sweep's condition with the trial's own policy and overrides, once
per elevator gain (sim.elevator_gain: elbow opening per rad of swing after a shin or foot touch); fixed gaits
(--gait a,b,omega) run the same episodes under the condition's overrides at each gain too.

    PYTHONPATH=<worktree of branch head> .venv/bin/python reports/experiments/free80/elevator_gain.py \
        reports/sweeps/free80 --condition free80 --gain 1.5 --gain 2.5 --gain 3.5 \
        --terrain wide_block --terrain tall_block --terrain extra_blocks --gait 0.8,0.4,3.141593

The policies are not retrained: a gain the policy did not train with is a run-time intervention, read as a hint
for what to train, not as a result. The arm at the trained gain must repeat the trial's outcomes (checked; a
difference exits 1). The policy is read from the sweep's data folder (`data/sweeps/<sweep name>/<trial>/ppo`).
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "ceiling"))
from episodes import checked_inputs, evaluate_episode, parse_gait, print_arms  # the helper in ../ceiling

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "select"))
from pipelines import load_records  # select/pipelines.py: a sweep's complete trial records

from hexpipe.evaluation.controllers import ControllerSpec


def _one(job: tuple[str, tuple[float, float, float] | None, str, int, tuple[str, ...]]) -> tuple[bool, float, float]:
    """(success, distance m, time s) of one replay: a policy folder or a fixed gait."""
    policy, gait, terrain, index, overrides = job
    spec = ControllerSpec("policy", policy) if gait is None else ControllerSpec("fixed", gait=gait)
    row = evaluate_episode(spec, terrain, index, overrides)
    return bool(row["success"]), float(row["distance"]), float(row["time"])


def _gain_set(overrides: list[str], gain: float) -> tuple[str, ...]:
    """The overrides with sim.elevator_gain set to `gain` (replacing the trial's own)."""
    return (*(o for o in overrides if not o.startswith("sim.elevator_gain=")), f"sim.elevator_gain={gain}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("report", type=Path, help="the sweep's report folder (reports/sweeps/NAME)")
    ap.add_argument("--condition", required=True)
    ap.add_argument("--data", type=Path, help="the sweep's data folder (default data/sweeps/NAME)")
    ap.add_argument("--gain", dest="gains", type=float, action="append", required=True)
    ap.add_argument("--terrain", dest="terrains", action="append", required=True)
    ap.add_argument("--gait", dest="gaits", action="append", default=[], metavar="A,B,OMEGA")
    ap.add_argument("--episodes", type=int, default=10)
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args()
    if not a.report.is_dir():
        raise SystemExit(f"error: {a.report} is not a folder")
    data = a.data or Path("data/sweeps") / a.report.name
    records = load_records([a.report], a.condition)
    if not records:
        raise SystemExit(f"error: no complete trial of condition {a.condition!r} in {a.report}")
    policies = {record["trial"]: data / record["trial"] / "ppo" for record in records}
    for policy in policies.values():
        if not policy.is_dir():
            raise SystemExit(f"error: {policy} is missing (the trial's policy; pass --data)")
    checked_inputs(records[0]["overrides"], a.terrains, [str(p) for p in policies.values()])
    gaits = [parse_gait(g) for g in a.gaits]
    arms = [f"gain {g:g}" for g in a.gains]
    mismatch = 0
    with ProcessPoolExecutor(a.workers) as pool:
        for terrain in a.terrains:
            print(f"\n{terrain}, {a.episodes} episodes a row; successes per elevator gain, "
                  "then the failures' distances")
            jobs, names, observed = [], [], []
            for record in records:
                names.append(record["trial"])
                jobs += [(str(policies[record["trial"]]), None, terrain, i, _gain_set(record["overrides"], g))
                         for g in a.gains for i in range(a.episodes)]
                trained = dict(o.split("=", 1) for o in record["overrides"]).get("sim.elevator_gain")
                eps = {ep["episode"]: ep for ep in record["episodes"]
                       if ep["controller"] == "policy" and ep["terrain"] == terrain}
                observed.append((trained, eps))
            base = records[0]["overrides"]
            for gait in gaits:
                names.append("fixed " + "/".join(f"{v:g}" for v in gait))
                jobs += [(None, gait, terrain, i, _gain_set(base, g)) for g in a.gains for i in range(a.episodes)]
            out = list(pool.map(_one, jobs))
            print_arms(names, arms, a.episodes, [(ok, d) for ok, d, _ in out], policy_width=22, arm_width=10)
            per_arm = [[0, 0, 0.0] for _ in a.gains]  # policies: successes, episodes, summed time of successes
            for k in range(len(records)):
                trained, eps = observed[k]
                for j, g in enumerate(a.gains):
                    runs = out[(k * len(a.gains) + j) * a.episodes:(k * len(a.gains) + j + 1) * a.episodes]
                    per_arm[j][0] += sum(ok for ok, _, _ in runs)
                    per_arm[j][1] += len(runs)
                    per_arm[j][2] += sum(t for ok, _, t in runs if ok)
                    if trained is not None and float(trained) == g:
                        for i, (ok, dist, _) in enumerate(runs):
                            if i in eps and (ok != bool(eps[i]["success"]) or abs(dist - eps[i]["distance"]) > 1e-6):
                                mismatch += 1
                                print(f"  REPLAY DIFFERS: {names[k]} episode {i}")
            print("  policies, all trials: " + "; ".join(
                f"gain {g:g} {s}/{n} crossed, {t / max(s, 1):.2f} s per crossing"
                for g, (s, n, t) in zip(a.gains, per_arm, strict=True)))
    if mismatch:
        print(f"{mismatch} replays at the trained gain differ from their trial's outcome")
        raise SystemExit(1)


if __name__ == "__main__":
    main()
