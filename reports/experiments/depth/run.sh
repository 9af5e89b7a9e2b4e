#!/usr/bin/env bash
# Does a policy lift for a block of any depth? Evaluates each policy folder on the training block (0.3 m deep) made
# 0.5, 0.7, 0.85 and 1.0 m deep (face at 1.0 m, 0.10 m high; 10 seeded episodes each, the best fixed gait a 0.4,
# b 0.4, omega pi beside it), then prints the policy's success per depth. See reports/experiments/README.md, "depth".
# Usage: bash reports/experiments/depth/run.sh OUT POLICY_DIR...   (POLICY_DIR: data/models/ppo or a sweep trial's ppo)
set -euo pipefail
out=${1:?usage: bash reports/experiments/depth/run.sh OUT POLICY_DIR...}; shift
mkdir -p "$out"
here=reports/experiments/depth
for policy in "$@"; do
  name=$(basename "$(dirname "$policy")")-$(basename "$policy")
  .venv/bin/hexpipe evaluate --no-summary --set "eval.policy_dir=$policy" \
    --set "eval.terrains=[single_block,wide_block]" \
    --set "eval.terrain_files=[$here/block_depth_05.yaml,$here/block_depth_07.yaml,$here/block_depth_085.yaml]" \
    --set eval.episodes=10 --set "eval.grid_a=[0.4]" --set "eval.grid_b=[0.4]" --set "eval.grid_omega=[3.141593]" \
    --set eval.record_video=false --set eval.workers=1 \
    --set "eval.out_dir=$out/$name/eval" --set "eval.report_dir=$out/$name/report" > "$out/$name.log" 2>&1 \
    || { echo "error: $policy: evaluate failed (its output: $out/$name.log)" >&2; exit 1; }
done
.venv/bin/python - "$out" <<'EOF'
import json, sys
from pathlib import Path
depths = {"single_block": 0.3, "block_depth_05": 0.5, "block_depth_07": 0.7, "block_depth_085": 0.85, "wide_block": 1.0}
print("policy | " + " | ".join(f"{d} m" for d in depths.values()) + " | best fixed gait, 1.0 m")
for report in sorted(Path(sys.argv[1]).glob("*/report/metrics.json")):
    m = json.loads(report.read_text())
    cells = [f"{m[t]['policy']['successes']}/{m[t]['policy']['episodes']}" for t in depths]
    fixed = m["wide_block"]["best_fixed"]
    print(f"{report.parent.parent.name} | " + " | ".join(cells) + f" | {fixed['successes']}/{fixed['episodes']}")
EOF
