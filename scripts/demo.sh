#!/usr/bin/env bash
# The demo: generates a synthetic tabletop recording and replays it through the GeoFusion
# nodelets, printing what they did. RVIZ=1 also opens rviz (needs a display).
set -euo pipefail
source "$(dirname "$0")/env.sh"
set +u
source "$GEOFUSION_WS/devel/setup.bash"
set -u

mkdir -p "$GEOFUSION_DATA/demo"
bag="$GEOFUSION_DATA/demo/synthetic_demo.bag"
say "generating the demo recording: $bag"
"$(catkin_find --first-only geofusion make_synthetic_bag)" --out "$bag" --frames 60 --seed 1 \
  --malformed-every 10

rviz=false
[ "${RVIZ:-0}" = "1" ] && rviz=true
log="$GEOFUSION_DATA/demo/demo_roslaunch.log"
say "starting the frame-by-frame detection viewer nodelet (roslaunch geofusion demo.launch; log: $log)"
roslaunch --skip-log-check geofusion demo.launch play:=false rviz:="$rviz" >"$log" 2>&1 &
launch_pid=$!
trap 'kill -INT $launch_pid 2>/dev/null || true' EXIT
for _ in $(seq 100); do  # wait until the viewer subscribes to the detections
  # a nodelet's subscriptions belong to its manager
  rostopic info /detections 2>/dev/null | grep -q geofusion_manager && break
  sleep 0.2
done
say "replaying the recording (rosbag play --clock); markers on /detection_viewer/detection_markers"
rosbag play --clock -q -d 1 "$bag"
sleep 2  # let the viewer log its final summary
kill -INT $launch_pid; wait $launch_pid || true
trap - EXIT
say "what the viewer said:"
grep -E "geofusion: " "$log" | grep -v "so far" | sed -e 's/\x1b\[[0-9;]*m//g' \
  -e 's/^\[ *\([A-Z]*\)\] \[[0-9., ]*\]: /  \1 /'
summary=$(grep "detection viewer so far" "$log" | tail -n 1 | sed -e 's/\x1b\[[0-9;]*m//g' -e 's/.*so far: //')
say "demo done: $summary"
say "the malformed detections the recording contains were skipped with a warning, as they must be"
