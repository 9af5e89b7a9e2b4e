#!/usr/bin/env bash
# The VAE settings grid of reports/experiments/README.md, "vae_grid": how the aux head's weight and the epochs move the
# distance probe (weight 8 with 60 epochs reaches 0.9; its policies cross less, so the default stays weight 1).
# Trains one encoder per setting on the committed collect (data/rollouts) into OUT/<name>, then prints each one's
# probes from its metrics.json. About 3 min per 30 epochs on 2 cores; the pipeline's own encoder is not touched.
# Usage: bash reports/experiments/vae_grid.sh [OUT]   (OUT defaults to /tmp/vae_grid)
set -euo pipefail
out=${1:-/tmp/vae_grid}
mkdir -p "$out"
specs=(
  "fw1:vae.feature_weight=1.0 vae.epochs=30"  # the default
  "fw2:vae.feature_weight=2.0 vae.epochs=30"
  "fw4:vae.feature_weight=4.0 vae.epochs=30"
  "fw8:vae.feature_weight=8.0 vae.epochs=30"
  "e60:vae.feature_weight=1.0 vae.epochs=60"
  "fw4e60:vae.feature_weight=4.0 vae.epochs=60"
  "fw8e60:vae.feature_weight=8.0 vae.epochs=60"  # the default of 1956217 only
  "fw4b01:vae.feature_weight=4.0 vae.epochs=30 vae.beta=0.1"
)
for spec in "${specs[@]}"; do
  name=${spec%%:*}
  args=()
  for s in ${spec#*:}; do args+=(--set "$s"); done
  .venv/bin/hexpipe train-vae "${args[@]}" --set "vae.out_dir=$out/$name" --set "vae.report_dir=$out/$name-report" \
    > "$out/$name.log" 2>&1 || { echo "error: $name: train-vae failed (its output: $out/$name.log)" >&2; exit 1; }
done
.venv/bin/python - "$out" "${specs[@]}" <<'EOF'
import json, sys
out, specs = sys.argv[1], sys.argv[2:]
print("setting | distance R² | height R² | distance kNN | height kNN | val recon")
for spec in specs:
    name, sets = spec.split(":", 1)
    m = json.load(open(f"{out}/{name}-report/metrics.json"))
    p = m["probe"]
    print(f"{sets} | {p['rise_distance_r2']:.3f} | {p['rise_height_r2']:.3f} | {p['rise_distance_knn_r2']:.3f} | "
          f"{p['rise_height_knn_r2']:.3f} | {m['val']['recon']:.3f}")
EOF
