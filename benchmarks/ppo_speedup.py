"""PPO training steps per second of this tree against an older commit, in alternating processes.

Usage: python benchmarks/ppo_speedup.py [--old f3adb97] [--rounds 3] [--steps 12288] [--encoder-dir DIR]
       [--out reports/bench/ppo_speedup.json] [--set key=value ...]

Issue 12 moved the frozen terrain encoder from the learner (one batched call between synchronous env steps) into
the env workers (`hexpipe.rl.features.TerrainEmbedding`). The env's own rate (`time/bare_env_steps_per_s`) then
includes the encoder, so `train_vs_bare` is not comparable across that change; the absolute training rate is. Each
round runs one short `train_ppo` per tree, both with the same encoder folder and params overrides, and the report
gives the per-tree medians and the median of the per-round ratios (new / old).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from speedup import ROOT, export_commit

from hexpipe.atomic import write_json

TRAINER = """
import json, sys
from hexpipe.config import load_params
from hexpipe.rl.train import train_ppo
params = load_params(sys.argv[1], json.loads(sys.argv[2]))
metrics = train_ppo(params, show_progress=False)
print(json.dumps({k: metrics[k] for k in ("time/train_steps_per_s", "time/bare_env_steps_per_s")}))
"""


def run_tree(tree: Path, overrides: list[str]) -> dict[str, float]:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    done = subprocess.run([sys.executable, "-c", TRAINER, str(tree / "params.yaml"), json.dumps(overrides)],
                          cwd=tree, env=env, capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(f"ppo_speedup: training in {tree} failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", default="f3adb97")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--steps", type=int, default=12288)
    parser.add_argument("--encoder-dir", type=lambda p: str(Path(p).resolve()), default=str(ROOT / "data/models/vae"),
                        help="read by both trees, each running in its own folder: resolved to an absolute path")
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    parser.add_argument("--out", default=str(ROOT / "reports/bench/ppo_speedup.json"))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        old_tree = Path(scratch) / "old"
        old_tree.mkdir()
        old_hash = export_commit(args.old, old_tree)
        trees = {"old": old_tree, "new": ROOT}
        rows: list[dict] = []
        for round_ in range(args.rounds):
            for name, tree in trees.items():
                out = Path(scratch) / f"{name}{round_}"
                overrides = [f"ppo.total_timesteps={args.steps}", f"ppo.encoder_dir={args.encoder_dir}",
                             f"ppo.out_dir={out}/ppo", f"ppo.report_dir={out}/report",
                             "ppo.checkpoint_every=1000000", *args.overrides]
                result = run_tree(tree, overrides)
                rows.append({"round": round_, "tree": name, **result})
                print(json.dumps(rows[-1]), flush=True)
    rate = {name: [r["time/train_steps_per_s"] for r in rows if r["tree"] == name] for name in trees}
    ratios = [new / old for old, new in zip(rate["old"], rate["new"], strict=True)]
    report = {"old_commit": old_hash, "steps": args.steps, "encoder_dir": args.encoder_dir,
              "overrides": args.overrides, "rounds": rows,
              "median_train_steps_per_s": {k: statistics.median(v) for k, v in rate.items()},
              "median_ratio_new_over_old": statistics.median(ratios)}
    out_path = Path(args.out)
    out_path.parent.mkdir(parents=True, exist_ok=True)
    write_json(out_path, report)
    medians = report["median_train_steps_per_s"]
    print(f"median train steps/s: old {medians['old']:.0f}, new {medians['new']:.0f}; "
          f"median ratio new/old {report['median_ratio_new_over_old']:.3f}")


if __name__ == "__main__":
    main()
