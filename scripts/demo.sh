#!/usr/bin/env bash
# The demo: generates the demo scene (built-in primitive models, a Fetch-like recording with its
# ground truth), runs GeoFusion on it with the offline runner, and prints what it found against
# the ground truth. Files land in $GEOFUSION_DATA/demo.
set -euo pipefail
source "$(dirname "$0")/env.sh"
set +u
source "$GEOFUSION_WS/devel/setup.bash"
set -u
out="$GEOFUSION_DATA/demo"
bin="$GEOFUSION_WS/devel/lib/geofusion"
say "generating the demo scene (cached after the first run): $out"
"$bin/generate_dataset" --suite demo --out-dir "$out" | grep -E "demo_01|generated"
say "running GeoFusion on $out/demo_01.bag (run_offline)"
"$bin/run_offline" --bag "$out/demo_01.bag" --out "$out/demo_01_geofusion.yaml" --method geofusion \
  --background "$out/demo_01_background.bt"
say "what it found against the ground truth:"
"$bin/evaluate_run" --results "$out/demo_01_geofusion.yaml" --ground-truth "$out/demo_01_gt.yaml"
say "the map (objects, contacts, trajectory, timings): $out/demo_01_geofusion.yaml"
say "the static background (OctoMap, objects removed): $out/demo_01_background.bt"
say "frames of the recording as PNG: $out/previews/"

# A screenshot of the result in rviz (rviz/geofusion.rviz), when Xvfb and ImageMagick are here:
# the recording replayed through the estimator nodelet with simulated time.
shot="$out/demo_01_rviz.png"
if command -v Xvfb >/dev/null && command -v import >/dev/null; then
  say "replaying the recording through the estimator nodelet and rviz under Xvfb for a screenshot"
  # A display Xvfb finds free itself (-displayfd writes its number), never one in use.
  displayfd="$out/.xvfb_display"
  rm -f "$displayfd"
  Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp 3>"$displayfd" >/dev/null 2>&1 &
  xvfb_pid=$!
  for _ in $(seq 50); do grep -q . "$displayfd" 2>/dev/null && break; sleep 0.1; done
  display=":$(head -n1 "$displayfd" 2>/dev/null)"
  [ "$display" != ":" ] || { say "Xvfb did not start"; exit 1; }
  DISPLAY="$display" roslaunch --skip-log-check geofusion replay.launch bag:="$out/demo_01.bag" \
    rviz:=true stop_at_end:=false >"$out/demo_rviz.log" 2>&1 &
  launch_pid=$!
  trap 'kill -INT $launch_pid 2>/dev/null || true; kill $xvfb_pid 2>/dev/null || true' EXIT
  sleep 28  # 2 s start delay, 12 s of recording, rviz settling
  DISPLAY="$display" import -window root "$shot"
  kill -INT $launch_pid; wait $launch_pid || true
  kill $xvfb_pid || true
  trap - EXIT
  say "rviz screenshot of the map: $shot"
else
  say "no Xvfb/ImageMagick: skipping the rviz screenshot"
fi
