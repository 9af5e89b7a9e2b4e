#!/usr/bin/env bash
# tall_fall's readout: the four `free80e` tall-block falls traced (arm "trained", gain 2.5), then replayed with the
# elevator at 1.5 and with task.fall_height 0.04; each printout goes to reports/experiments/tall_fall/.
#   cd <worktree of branch head, data/ linked> && bash /work/main/reports/experiments/tall_fall/replay.sh /work/main
set -euo pipefail
MAIN=${1:?the main checkout, where the printouts go}
OUT=$MAIN/reports/experiments/tall_fall
PY=$MAIN/.venv/bin/python
TRAINED=(--set sim.heading_gain=1 --set sim.elevator_gain=2.5 --set task.lift_teacher=60 --set task.stride_reflex=0.35
  --set "task.lift_reflex_zone=[0.6,1.05]" --set "cpg.lower=[0.6,0.2,3.141593]" --set "cpg.initial=[0.6,0.2,3.926991]"
  --set "cpg.upper=[0.8,0.5,4.712389]" --set ppo.encoder_dir=data/encoders/63bc9753625a595a)
for seed in 2000 2001 2002; do  # the policies are the tall_fall sweep's; say so in one line, not a silent stop
  [ -d "data/sweeps/tall_fall/free80e-seed$seed/ppo" ] || {
    echo "error: data/sweeps/tall_fall/free80e-seed$seed/ppo is missing (run the tall_fall sweep in this worktree first)" >&2; exit 2; }
done
declare -A ARMS=([trained]="" [gain1.5]="--set sim.elevator_gain=1.5" [fall0.04]="--set task.fall_height=0.04")
header="# $(date -u +%Y-%m-%dT%H:%M:%SZ), $(lscpu | sed -n 's/^Model name: *//p') family $(lscpu | sed -n 's/^CPU family: *//p') model $(lscpu | sed -n 's/^Model: *//p'), branch head ($(git rev-parse --short HEAD))"
for ep in 2000:6 2000:8 2001:4 2002:0; do
  seed=${ep%:*}; n=${ep#*:}
  for arm in trained gain1.5 fall0.04; do
    # shellcheck disable=SC2206
    extra=(${ARMS[$arm]})
    cmd=(fall_trace.py data/sweeps/tall_fall/free80e-seed$seed/ppo tall_block "$n" "${TRAINED[@]}" "${extra[@]}")
    { echo "$header"; echo "# PYTHONPATH=. \$MAIN/.venv/bin/python \$MAIN/reports/experiments/tall_fall/${cmd[*]}"
      PYTHONPATH=. "$PY" "$OUT/${cmd[0]}" "${cmd[@]:1}" 2>/dev/null; } > "$OUT/trace_seed${seed}_ep${n}_${arm}.txt"
    sed -n 3p "$OUT/trace_seed${seed}_ep${n}_${arm}.txt"
  done
done
# How close a crossing comes: each tall-block episode's lowest clearance, for two fixed gaits (gain 2.5, heading 1,
# the settings of elev_free/fixed_gaits_e25.csv) and the three retrained policies.
FIXED=(--set sim.heading_gain=1 --set sim.elevator_gain=2.5 --set task.lift_teacher=60 --set task.stride_reflex=0.35
  --set "task.lift_reflex_zone=[0.6,1.05]" --set "cpg.lower=[0.2,0.2,3.141593]" --set "cpg.upper=[0.8,0.5,6.283185]"
  --set "cpg.initial=[0.6,0.2,3.926991]" --set ppo.encoder_dir=data/encoders/63bc9753625a595a)
{ echo "$header"; echo "# bash \$MAIN/reports/experiments/tall_fall/replay.sh \$MAIN (its last loop): fall_trace.py's summary line per episode"
  for n in 0 1 2 3 4 5 6 7 8 9; do
    for gait in 0.6,0.4,3.141593 0.8,0.4,3.141593; do
      echo -n "gait $gait: "; PYTHONPATH=. "$PY" "$OUT/fall_trace.py" - tall_block "$n" --gait "$gait" "${FIXED[@]}" 2>/dev/null | head -1
    done
    for seed in 2000 2001 2002; do
      echo -n "free80e-seed$seed: "
      PYTHONPATH=. "$PY" "$OUT/fall_trace.py" "data/sweeps/tall_fall/free80e-seed$seed/ppo" tall_block "$n" "${TRAINED[@]}" 2>/dev/null | head -1
    done
  done; } > "$OUT/clearance.txt"
