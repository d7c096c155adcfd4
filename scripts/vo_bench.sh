#!/usr/bin/env bash
# The visual odometry benchmark (docs/visual_odometry.md): generates or reuses the "vo" (table
# orbit, 15 s) and "vo_fast" (fast head turns, 10 s) suites at 30 Hz, runs vo_benchmark on each
# (OpenCV on one thread) and writes the TUM trajectories, one JSON per scene and report.md to
# results/vo/ (or VO_OUT). Exit code 1 when a scene's run fails.
set -euo pipefail
source "$(dirname "$0")/env.sh"
set +u
source "$GEOFUSION_WS/devel/setup.bash"
set -u
out="${VO_OUT:-$GEOFUSION_SRC/results/vo}"
bin="$GEOFUSION_WS/devel/lib/geofusion"
mkdir -p "$out"
start=$(date +%s)
say "visual odometry benchmark: results in $out"
report="$out/report.md"
{
  echo "# Visual odometry benchmark"
  echo
  echo "Generated $(date -u +%Y-%m-%d) on $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)),"
  echo "OpenCV on one thread. ATE: RMSE of camera positions after a rigid alignment (Umeyama, no"
  echo "scale). RPE: over 1 s. Lost: frames without a pose."
  echo
  echo "| scene | frames | path (m) | lost | restarts | keyframes | ATE RMSE (cm) | ATE max (cm) | RPE 1 s (cm) | RPE 1 s (deg) | median ms | p95 ms |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
} > "$report.tmp"
for suite in vo vo_fast; do
  data="$GEOFUSION_DATA/$suite"
  "$bin/generate_dataset" --suite "$suite" --out-dir "$data" --previews 1 | grep -E "^generate_dataset:" || true
  for request in "$data"/*.request; do
    scene=$(basename "$request" .request)
    "$bin/vo_benchmark" --bag "$data/$scene.bag" --ground-truth "$data/${scene}_gt.yaml" \
      --out-dir "$out" --quiet | sed 's/^vo_benchmark: /  /'
    /usr/bin/python3 - "$out/${scene}_vo.json" >> "$report.tmp" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
print("| %s | %d | %.2f | %d | %d | %d | %.2f | %.2f | %.2f | %.2f | %.1f | %.1f |" % (
    j["scene"], j["frames"], j["path_length_m"], j["lost_frames"], j["restarts"], j["keyframes"],
    100 * j["ate_rmse_m"], 100 * j["ate_max_m"], 100 * j["rpe_translation_rmse_m"],
    j["rpe_rotation_rmse_deg"], j["time_ms_median"], j["time_ms_p95"]))
PY
  done
done
mv "$report.tmp" "$report"
cat "$report"
say "visual odometry benchmark done in $(( $(date +%s) - start )) s: $report"
