#!/usr/bin/env bash
# `vae_seeds` in reports/experiments/README.md: the aux head's weight, epochs and beta on today's collect, each on
# vae.seed 0, 1 and 2 (the seed also draws the held-out episodes, so the spread is the probe's own). One encoder per
# setting and seed into OUT/<name>-s<seed>; then prints each one's probes and their mean over the seeds.
# About 70 s per 30 epochs on 2 cores; the pipeline's own encoder is not touched.
# Usage: bash reports/experiments/vae_seeds/grid.sh [OUT]   (OUT defaults to /tmp/vae_seeds)
#        SEEDS="0 1 2 3 4 5" SPECS="fw1 fw8" bash reports/experiments/vae_seeds/grid.sh OUT   (other seeds, some settings)
set -euo pipefail
out=${1:-/tmp/vae_seeds}
mkdir -p "$out"
specs=(
  "fw1:vae.feature_weight=1.0 vae.epochs=30"  # the default
  "fw4:vae.feature_weight=4.0 vae.epochs=30"
  "fw8:vae.feature_weight=8.0 vae.epochs=30"
  "fw4b01:vae.feature_weight=4.0 vae.epochs=30 vae.beta=0.1"
  "fw8e60:vae.feature_weight=8.0 vae.epochs=60"
)
seeds=(${SEEDS:-0 1 2})
if [ -n "${SPECS:-}" ]; then
  kept=()
  for spec in "${specs[@]}"; do [[ " $SPECS " == *" ${spec%%:*} "* ]] && kept+=("$spec"); done
  specs=("${kept[@]}")
fi
for spec in "${specs[@]}"; do
  name=${spec%%:*}
  for seed in "${seeds[@]}"; do
    [ -f "$out/$name-s$seed-report/metrics.json" ] && continue
    args=(--set "vae.seed=$seed")
    for s in ${spec#*:}; do args+=(--set "$s"); done
    .venv/bin/hexpipe train-vae "${args[@]}" --set "vae.out_dir=$out/$name-s$seed" \
      --set "vae.report_dir=$out/$name-s$seed-report" > "$out/$name-s$seed.log" 2>&1 \
      || { echo "error: $name seed $seed: train-vae failed (its output: $out/$name-s$seed.log)" >&2; exit 1; }
  done
done
.venv/bin/python - "$out" "${seeds[*]}" "${specs[@]}" <<'PY'
import json, sys
out, seeds, specs = sys.argv[1], [int(s) for s in sys.argv[2].split()], sys.argv[3:]
n = len(seeds)
print("setting | seed | distance R² | height R² | distance kNN | height kNN | val recon")
for spec in specs:
    name, sets = spec.split(":", 1)
    rows = []
    for seed in seeds:
        m = json.load(open(f"{out}/{name}-s{seed}-report/metrics.json"))
        p = m["probe"]
        rows.append((p["rise_distance_r2"], p["rise_height_r2"], p["rise_distance_knn_r2"], p["rise_height_knn_r2"],
                     m["val"]["recon"]))
        print(f"{sets} | {seed} | " + " | ".join(f"{v:.3f}" for v in rows[-1]))
    mean = [sum(r[i] for r in rows) / n for i in range(5)]
    print(f"{sets} | mean | " + " | ".join(f"{v:.3f}" for v in mean))
PY
