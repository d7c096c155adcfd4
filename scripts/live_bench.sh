#!/usr/bin/env bash
# make live-bench (docs/BENCHMARK.md, "Live"): the robot's launch (replay.launch) fed by rosbag play
# at 1x and 2x, with the other core idle and busy, on the demo recording and on a YCB-Video bench
# recording (bench_rgb_01, when the YCB-Video models are there), and once with the visual odometry
# (the vo suite's recording). Per run: latency from the frame to its ObjectMap and TF frames,
# frames sent and maps received, drops by reason, the manager's CPU (bench/live_bench.py).
# JSON per run, summary.json and latency.png in results/live/ (LIVE_OUT).
#   RATES="1 2"  LOADS="idle busy"  MODELS=DIR (YCB-Video; default ../shared/data/ycb_video)
set -euo pipefail
source "$(dirname "$0")/env.sh"
bash "$GEOFUSION_SRC/scripts/python_env.sh"
set +u
source "$GEOFUSION_WS/devel/setup.bash"
set -u
out="${LIVE_OUT:-$GEOFUSION_SRC/results/live}"
bin="$GEOFUSION_WS/devel/lib/geofusion"
models_dir="${MODELS:-${GEOFUSION_YCB_DIR:-$GEOFUSION_SRC/../shared/data/ycb_video}}"
mkdir -p "$out"
rm -f "$out"/run_*.json
"$bin/generate_dataset" --suite demo --out-dir "$GEOFUSION_DATA/demo" | grep -E "^generate_dataset:" || true
recordings=("demo:$GEOFUSION_DATA/demo/demo_01.bag:")
if [ -d "$models_dir" ]; then
  "$bin/generate_dataset" --suite bench_rgb --scenes bench_rgb_01 --out-dir "$GEOFUSION_DATA/bench_rgb" \
    --models "$models_dir" | grep -E "^generate_dataset:" || true
  recordings+=("bench_rgb_01:$GEOFUSION_DATA/bench_rgb/bench_rgb_01.bag:model_set:=ycb_video models_dir:=$models_dir")
else
  say "no YCB-Video models in $models_dir: the demo recording only"
fi
n=0
run() {  # name bag rate load odometry launch-args...
  local name="$1" bag="$2" rate="$3" load="$4" odometry="$5"
  shift 5
  local args=()
  for a in "$@"; do args+=(--launch-arg "$a"); done
  n=$((n + 1))
  local load_flag=()
  [ "$load" = busy ] && load_flag=(--load)
  /usr/bin/python3 "$GEOFUSION_SRC/bench/live_bench.py" --bag "$bag" --rate "$rate" \
    "${load_flag[@]}" --odometry "$odometry" "${args[@]}" \
    --out "$out/run_${name}_${rate}x_${load}_${odometry}.json" || say "run $name ${rate}x $load failed"
}
for rec in "${recordings[@]}"; do
  IFS=: read -r name bag extra <<< "$rec"
  read -r -a extra_args <<< "$extra"
  for rate in ${RATES:-1 2}; do
    for load in ${LOADS:-idle busy}; do
      run "$name" "$bag" "$rate" "$load" tf "${extra_args[@]}"
    done
  done
done
# The visual odometry's own recording (30 Hz colour, its wheel odometry not used): once, 1x idle.
"$bin/generate_dataset" --suite vo --out-dir "$GEOFUSION_DATA/vo" | grep -E "^generate_dataset:" || true
vo_bag=$(ls "$GEOFUSION_DATA"/vo/*.bag 2>/dev/null | head -1)
[ -n "$vo_bag" ] && run vo "$vo_bag" 1 idle visual
"$GEOFUSION_VENV/bin/python" "$GEOFUSION_SRC/bench/live_report.py" --dir "$out"
