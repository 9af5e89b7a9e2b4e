#!/usr/bin/env bash
# fall04's read 1: each fall04 trial against its elev_free twin. Training: ppo/metrics.json and ppo/selection.json
# compared byte for byte; evaluation: eval/results.csv's columns 1-25 (all but the wall-clock wall_s), and the rows
# that differ, columns 1-10 (< fall04, > elev_free).
#   bash reports/experiments/fall04/same_training.sh [reports/sweeps]     # from the main checkout
set -euo pipefail
SWEEPS=${1:-reports/sweeps}
for sweep in fall04 elev_free; do
  [ -d "$SWEEPS/$sweep" ] || { echo "error: $SWEEPS/$sweep: no such sweep folder (run from the main checkout)" >&2; exit 2; }
done
for d in "$SWEEPS"/fall04/free80e04-seed*/; do
  s=${d%/}; s=${s##*seed}; t=$SWEEPS/elev_free/free80e-seed$s
  m=$(cmp -s "$d/ppo/metrics.json" "$t/ppo/metrics.json" && echo same || echo DIFF)
  sel=$(cmp -s "$d/ppo/selection.json" "$t/ppo/selection.json" && echo same || echo DIFF)
  rows=$(diff <(cut -d, -f1-25 "$d/eval/results.csv") <(cut -d, -f1-25 "$t/eval/results.csv") | grep -c '^<' || true)
  echo "seed $s: metrics $m, selection $sel, evaluation rows that differ: $rows"
  diff <(cut -d, -f1-10 "$d/eval/results.csv") <(cut -d, -f1-10 "$t/eval/results.csv") | grep '^[<>]' | sed 's/^/    /' || true
done
