set -e
cd /work/main
export PATH=/work/main/.venv/bin:$PATH
run() {  # name, extra collect sets...
  n=$1; shift
  d=/tmp/cg/$n
  date -u +"%H:%M:%S start $n"
  hexpipe collect --set collect.out_dir=$d/rollouts "$@" > $d.collect.log 2>&1
  cp reports/collect.json $d.collect.json
  hexpipe train-vae --set vae.data_dir=$d/rollouts --set vae.out_dir=$d/vae --set vae.report_dir=$d/vaereport > $d.vae.log 2>&1
  date -u +"%H:%M:%S end $n"
}
run A --set "collect.cpg_lower=[0.4,0.2,3.141593]" --set "collect.cpg_upper=[0.8,0.5,4.712389]" --set collect.action_order=2
run B --set "collect.cpg_lower=[0.4,0.2,3.141593]" --set "collect.cpg_upper=[0.4,0.5,3.926991]" --set collect.action_order=2
run D --set collect.episodes=200
run E --set "collect.cpg_lower=[0.4,0.2,3.141593]" --set "collect.cpg_upper=[0.4,0.5,3.926991]" --set collect.action_order=2 --set collect.episodes=200
