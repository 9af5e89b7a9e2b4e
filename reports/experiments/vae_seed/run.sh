#!/usr/bin/env bash
# Does the policy's adaptation depend on which encoder it gets? Two more VAEs from the same rollouts with other
# seeds (vae.seed 1 and 2; the pipeline's is 0), then PPO seed 0 on each, with the `train_dist` sweep's budget and
# evaluation. Run from the repository root after `dvc repro` (it reads data/rollouts).
set -euo pipefail
export PATH="$PWD/.venv/bin:$PATH" PYTHONPATH="$PWD"
for seed in 1 2; do
  out=data/sweeps/encoders/vseed$seed
  if [ ! -f "$out/encoder.pt" ]; then
    hexpipe train-vae --set vae.seed=$seed --set vae.out_dir=$out --set vae.report_dir=$out-report \
      > "/tmp/vae_seed$seed.log" 2>&1 || { echo "error: train-vae with vae.seed=$seed failed; see /tmp/vae_seed$seed.log" >&2; exit 1; }
  fi
  python - "$out-report/metrics.json" "$seed" <<'PY'
import json, sys
probe = json.load(open(sys.argv[1]))["probe"]
print(f"vae.seed={sys.argv[2]}: distance R2 {probe['rise_distance_r2']:.3f}, height R2 {probe['rise_height_r2']:.3f}")
PY
done
hexpipe sweep --name vae_seed --seeds 0 \
  --condition "vseed1:ppo.encoder_dir=data/sweeps/encoders/vseed1" \
  --condition "vseed2:ppo.encoder_dir=data/sweeps/encoders/vseed2" \
  --set eval.episodes=10 --set "eval.grid_a=[0.4]" --set "eval.grid_b=[0.4]" --set "eval.grid_omega=[3.141593]" --cpus 2
