#!/bin/bash
# Issue 10: the `floors` condition (lift b >= 0.2, stride frequency omega >= pi) over seeds 0-7, 8 trials at once
# on the lent 16-core machine (Python 3.12): unpack the cp312 packages, build PyBullet, run the sweep, pack records.
# Run there from the repository root as `bash .dev/device_floors.sh`, with .dev/ carried: site312.txz (the cp312
# wheels hexpipe needs, Ray trimmed to its core), pbtrim.txz (PyBullet 3.2.7's sdist without its data and examples)
# and vae/ (data/models/vae's encoder). What ran and what came back: reports/experiments/README.md, "floors".
set -uo pipefail
export PYTHONUNBUFFERED=1
T0=$(date +%s); log() { echo "[$(( $(date +%s) - T0 )) s] $*"; }
log "$(nproc) cpus; $(python3 --version); $(free -g | awk '/Mem/ {print $2}') GiB; shm $(df -h /dev/shm | awk 'NR==2 {print $2}')"
mkdir -p /tmp/site /tmp/pb
xz -dc .dev/site312.txz | tar xf - -C /tmp/site || { log "unpack failed"; exit 1; }
xz -dc .dev/pbtrim.txz | tar xf - -C /tmp/pb || exit 1
mkdir -p data/models/vae && cp .dev/vae/encoder.pt .dev/vae/encoder.json data/models/vae/
log unpacked
( cd /tmp/pb/pbtrim && PYTHONPATH=/tmp/site python3 setup.py build_ext --inplace > $OUT/pybullet_build.log 2>&1 ) || { tail -40 $OUT/pybullet_build.log; log "pybullet build failed"; exit 1; }
cp /tmp/pb/pbtrim/examples/pybullet/gym/pybullet*.so /tmp/site/ && log "pybullet built"
rm -f $OUT/pybullet_build.log
cat > /tmp/site/sitecustomize.py <<'PY'
# device only: PyBullet built here crashes when imported before torch; no git repo travels, so dvclive must not look.
import torch  # noqa: F401
import dvclive.live
dvclive.live.Live._init_dvc = lambda self: None
PY
export PYTHONPATH=/tmp/site:$PWD CUDA_VISIBLE_DEVICES=
python3 -c "import pybullet, stable_baselines3, ray, hexpipe.cli, hexpipe.sweep.trial; print('imports ok')" || { log "imports failed"; exit 1; }
LEFT=$(( ${BUDGET:-560} - ($(date +%s) - T0) ))
log "sweep, $LEFT s left"
timeout $LEFT python3 -c "from hexpipe.cli import app; app()" sweep --name floors --seeds 0,1,2,3,4,5,6,7 \
  --condition "floors:cpg.lower=[0.05,0.2,3.141593];cpg.initial=[0.25,0.2,4.712389]" --set eval.episodes=10 \
  --set "eval.grid_a=[0.4]" --set "eval.grid_b=[0.4]" --set "eval.grid_omega=[3.141593]" --cpus 16 \
  > $OUT/sweep.log 2>&1
log "sweep rc=$?"
tail -30 $OUT/sweep.log
tar czf $OUT/floors.tgz reports/sweeps/floors data/sweeps/floors 2>&1 | tail -3
log "packed $(du -h $OUT/floors.tgz | cut -f1)"
