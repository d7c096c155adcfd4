#!/usr/bin/env bash
# make bench-real (docs/BENCHMARK.md, "Real frames"): every method on the real YCB-Video frames of
# ../shared/data/real (imported by import_dataset, detections 2-4 cm off along the ray) with the
# benchmark's evaluation (bench.sh SUITE=real: results/real/report.md), then the visual odometry
# beside Open3D's and OpenCV's RGB-D odometry on the 7-Scenes frames (results/real/vo_real.md).
# Open3D and OpenCV-contrib come from PyPI into their own environment (~/.cache/geofusion/venv-real,
# pinned in bench/requirements-real.txt).
set -euo pipefail
source "$(dirname "$0")/env.sh"
real="${GEOFUSION_REAL_DIR:-$GEOFUSION_SRC/../shared/data/real}"
out="${BENCH_OUT:-$GEOFUSION_SRC/results/real}"
[ -d "$real/ycbv_video" ] && [ -d "$real/7scenes_redkitchen" ] ||
  { say "no real frames in $real (set GEOFUSION_REAL_DIR)"; exit 1; }
SUITE=real BENCH_OUT="$out" bash "$GEOFUSION_SRC/scripts/bench.sh"
# An environment of its own, not over Debian's site packages: opencv-contrib-python 5.1 needs
# numpy >= 2, which Debian 12's scipy and matplotlib (numpy < 1.27) must not see. Every version
# it installs is pinned (bench/requirements-real.txt); vo_real.py needs nothing else.
venv="$HOME/.cache/geofusion/venv-real"
requirements="$GEOFUSION_SRC/bench/requirements-real.txt"
if ! "$venv/bin/python" -c 'import open3d, cv2; cv2.Odometry' 2>/dev/null ||
   ! cmp -s "$requirements" "$venv/requirements-real.txt"; then
  say "installing $(grep -v '^#' "$requirements" | tr '\n' ' ')into $venv"
  rm -rf "$venv"
  /usr/bin/python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet --disable-pip-version-check -r "$requirements"
  "$venv/bin/pip" check
  cp "$requirements" "$venv/requirements-real.txt"
fi
set +u
source "$GEOFUSION_WS/devel/setup.bash"
set -u
bin="$GEOFUSION_WS/devel/lib/geofusion"
# A folder of its own: in "real" bench.sh would take this recording (no detections) for a scene
# of the suite and fail the next `make bench-real`.
data="$GEOFUSION_DATA/real_vo"
"$bin/import_dataset" --in "$real/7scenes_redkitchen" --out-dir "$data" --name 7scenes_redkitchen \
  --model-set primitives --detections none --quiet
"$bin/vo_benchmark" --bag "$data/7scenes_redkitchen.bag" \
  --ground-truth "$data/7scenes_redkitchen_gt.yaml" --out-dir "$out/vo" --quiet
"$venv/bin/python" "$GEOFUSION_SRC/bench/vo_real.py" --frames "$real/7scenes_redkitchen" \
  --ours "$out/vo/7scenes_redkitchen_vo.json" --out "$out"
say "report: $out/report.md (every method on the YCB-Video frames), $out/vo_real.md (odometry)"
