#!/usr/bin/env bash
# The benchmark (docs/BENCHMARK.md): generates or reuses each suite (SUITE="bench bench_rgb
# bench_iid" by default, or one of them, or demo, or real: the real frames imported), runs FbF, B-SLAM, R-Front and GeoFusion on every
# scene with the offline runner, evaluates each run against the ground truth (evaluate_run) and
# writes report.md, summary.json and the figures (bench_report.py, COCO mAP by pycocotools) to
# results/<suite>/ (or BENCH_OUT/<suite> with several suites, BENCH_OUT with one); with several
# suites also results/report.md (BENCH_OUT/report.md), a table per suite.
#   MODELS=DIR     YCB-Video models folder (default $GEOFUSION_YCB_DIR, else ../shared/data/ycb_video)
#   GUARD=1        exit 1 unless GeoFusion beats FbF on mAP50:95 and precision50 (CI's guard)
#   METHODS="..."  a subset of: fbf fbfr bslam rfront geofusion (fbfr: FbF with depth refinement)
#   JOBS=N         runs at once (default: the number of cores); the results do not depend on it
#   PARAMS=FILE    configuration file for every method (run_offline --params; the method itself
#                  is set per run), PARAMS_<method>=FILE for one method (e.g. PARAMS_geofusion)
set -euo pipefail
source "$(dirname "$0")/env.sh"
bash "$GEOFUSION_SRC/scripts/python_env.sh"
set +u
source "$GEOFUSION_WS/devel/setup.bash"
set -u
read -r -a suites <<< "${SUITE:-bench bench_rgb bench_iid}"
if [ ${#suites[@]} -gt 1 ]; then  # each suite on its own (this script again), then one report
  results_root="${BENCH_OUT:-$GEOFUSION_SRC/results}"
  dirs=()
  status=0
  for suite in "${suites[@]}"; do
    SUITE="$suite" BENCH_OUT="$results_root/$suite" bash "$0" || status=$?
    [ -f "$results_root/$suite/summary.json" ] && dirs+=("$results_root/$suite")
  done
  if [ ${#dirs[@]} -gt 0 ]; then
    "$GEOFUSION_VENV/bin/python" "$GEOFUSION_SRC/src/tools/bench_report.py" \
      --combine "${dirs[@]}" --out "$results_root"
  fi
  [ $status -eq 0 ] || say "a suite failed (exit $status)"
  exit $status
fi
suite="${suites[0]}"
data="$GEOFUSION_DATA/$suite"
out="${BENCH_OUT:-$GEOFUSION_SRC/results/$suite}"
bin="$GEOFUSION_WS/devel/lib/geofusion"
models=()
[ -n "${MODELS:-}" ] && models=(--models "$MODELS")
start=$(date +%s)

say "benchmark on suite '$suite': data in $data, results in $out"
if [ "$suite" = real ]; then  # the real frames of ../shared/data/real, imported (make bench-real)
  real="${GEOFUSION_REAL_DIR:-$GEOFUSION_SRC/../shared/data/real}"
  [ -d "$real/ycbv_video" ] || { say "no real frames in $real (GEOFUSION_REAL_DIR)"; exit 1; }
  for video in "$real"/ycbv_video/[0-9]*/; do
    name="ycbv_$(basename "$video")"
    # Detections from the truth, 2-4 cm off along the ray (a colour-only estimator's error).
    "$bin/import_dataset" --in "$video" --out-dir "$data" --name "$name" --ray-bias 0.02,0.04 \
      "${models[@]}" --quiet
  done
  PARAMS="${PARAMS:-$GEOFUSION_SRC/bench/params/real_frames.yaml}"  # every 30 Hz frame a keyframe
else
  "$bin/generate_dataset" --suite "$suite" --out-dir "$data" "${models[@]}" | grep -E "^generate_dataset:" || true
fi
mkdir -p "$out/runs" "$out/eval"
shopt -s nullglob
bags=()
for request in "$data"/*.request; do  # the suite's own scenes (generate_dataset's cache keys)
  bags+=("${request%.request}.bag")
done
[ ${#bags[@]} -gt 0 ] || { say "no recordings in $data"; exit 1; }
# One method on one scene: the run, then its evaluation (its output printed whole at its end).
run_one() {
  local bag="$1" method="$2" scene gt model_set results params_var params_file params log scene_id
  local bop_dataset=()
  scene=$(basename "$bag" .bag)
  gt="$data/${scene}_gt.yaml"
  model_set=$(sed -n 's/^model_set: *//p' "$gt" | head -1)
  results="$out/runs/$scene/$method.yaml"
  params_var="PARAMS_$method"
  params_file="${!params_var:-${PARAMS:-}}"
  params=()
  [ -n "$params_file" ] && params=(--params "$params_file")
  # BOP results beside the run (docs/results.md): scene id the scene's number (bench_03: 3).
  scene_id=$(printf '%s' "$scene" | sed -n 's/.*[^0-9]\([0-9][0-9]*\)$/\1/p')
  scene_id=$((10#${scene_id:-0}))
  # ... and the ground truth at the keyframes as a BOP dataset, once a scene (every method has
  # the same keyframes), so that BOP's own toolkit can score them (docs/BENCHMARK.md).
  # The dataset's name is BOP's for the YCB-Video set (ycbv), else the model set's.
  local bop_name="$model_set"
  [ "$model_set" = ycb_video ] && bop_name=ycbv
  [ "$method" = geofusion ] && bop_dataset=(--bop-dataset "$out/bop/$bop_name" --bop-scene-id "$scene_id")
  log=$(
    "$bin/run_offline" --bag "$bag" --out "$results" "${params[@]}" --method "$method" \
      --model-set "$model_set" "${models[@]}" --bop-results "${results%.yaml}.bop.csv" \
      --bop-scene-id "$scene_id" --quiet 2>&1 | sed 's/^run_offline: /  /'
    "$bin/evaluate_run" --ground-truth "$gt" --results "$results" --model-set "$model_set" \
      "${models[@]}" --json "$out/eval/$scene/$method.json" "${bop_dataset[@]}" --quiet 2>&1
  ) || { printf '%s\n' "$log"; say "$scene / $method failed"; touch "$results.failed"; return 1; }
  printf '%s\n' "$log"
}
# JOBS runs at once (default: one a core); every run is single-threaded and repeatable, so the
# results are those of one at a time (times aside: JOBS=1 for time figures on a busy machine).
jobs_max="${JOBS:-$(nproc)}"
[[ "$jobs_max" =~ ^[1-9][0-9]*$ ]] || { say "JOBS must be a positive integer (got '$jobs_max')"; exit 2; }
say "$jobs_max run(s) at once (JOBS)"
for bag in "${bags[@]}"; do
  scene=$(basename "$bag" .bag)
  mkdir -p "$out/runs/$scene" "$out/eval/$scene"
  for method in ${METHODS:-fbf fbfr bslam rfront geofusion}; do
    rm -f "$out/runs/$scene/$method.yaml.failed"
    while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do wait -n || true; done
    run_one "$bag" "$method" &
  done
done
wait  # a failed run leaves <results>.failed beside its results
failed=("$out"/runs/*/*.failed)
[ ${#failed[@]} -eq 0 ] || { say "${#failed[@]} run(s) failed: ${failed[*]}"; exit 1; }
say "runs and evaluation took $(( $(date +%s) - start )) s; writing the report"
guard=()
[ "${GUARD:-0}" = 1 ] && guard=(--guard)
"$GEOFUSION_VENV/bin/python" "$GEOFUSION_SRC/src/tools/bench_report.py" --eval-dir "$out/eval" \
  --out "$out" --suite "$suite" "${guard[@]}"
say "report: $out/report.md (summary.json, figures beside it)"
