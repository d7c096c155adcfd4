#!/usr/bin/env bash
# make bench-real (docs/BENCHMARK.md, "Real frames"): every method on the real YCB-Video frames of
# ../shared/data/real (imported by import_dataset, detections 2-4 cm off along the ray) with the
# benchmark's evaluation (bench.sh SUITE=real: results/real/report.md), then the visual odometry
# beside Open3D's and OpenCV's RGB-D odometry on the 7-Scenes frames (results/real/vo_real.md).
# Open3D and OpenCV-contrib come from PyPI into their own environment (~/.cache/geofusion/venv-real).
set -euo pipefail
source "$(dirname "$0")/env.sh"
real="${GEOFUSION_REAL_DIR:-$GEOFUSION_SRC/../shared/data/real}"
out="${BENCH_OUT:-$GEOFUSION_SRC/results/real}"
[ -d "$real/ycbv_video" ] && [ -d "$real/7scenes_redkitchen" ] ||
  { say "no real frames in $real (set GEOFUSION_REAL_DIR)"; exit 1; }
SUITE=real BENCH_OUT="$out" bash "$GEOFUSION_SRC/scripts/bench.sh"
venv="$HOME/.cache/geofusion/venv-real"
if ! "$venv/bin/python" -c 'import open3d, cv2; cv2.Odometry' 2>/dev/null; then
  say "installing open3d 0.20.0 and opencv-contrib-python 5.1.0.95 into $venv"
  /usr/bin/python3 -m venv --system-site-packages "$venv"
  "$venv/bin/pip" install --quiet --disable-pip-version-check 'open3d==0.20.0' \
    'opencv-contrib-python==5.1.0.95'
fi
set +u
source "$GEOFUSION_WS/devel/setup.bash"
set -u
bin="$GEOFUSION_WS/devel/lib/geofusion"
data="$GEOFUSION_DATA/real"
"$bin/import_dataset" --in "$real/7scenes_redkitchen" --out-dir "$data" --name 7scenes_redkitchen \
  --model-set primitives --detections none --quiet
"$bin/vo_benchmark" --bag "$data/7scenes_redkitchen.bag" \
  --ground-truth "$data/7scenes_redkitchen_gt.yaml" --out-dir "$out/vo" --quiet
"$venv/bin/python" "$GEOFUSION_SRC/bench/vo_real.py" --frames "$real/7scenes_redkitchen" \
  --ours "$out/vo/7scenes_redkitchen_vo.json" --out "$out"
say "report: $out/report.md (every method on the YCB-Video frames), $out/vo_real.md (odometry)"
