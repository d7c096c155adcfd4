#!/usr/bin/env bash
# The demo: generates a synthetic tabletop recording and replays it through the GeoFusion
# nodelets, printing what they did. RVIZ=1 also opens rviz.
set -euo pipefail
source "$(dirname "$0")/env.sh"
set +u
source "$GEOFUSION_WS/devel/setup.bash"
set -u

mkdir -p "$GEOFUSION_DATA/demo"
bag="$GEOFUSION_DATA/demo/synthetic_demo.bag"
say "generating the demo recording: $bag"
make_synthetic_bag=$(catkin_find --first-only geofusion make_synthetic_bag)
"$make_synthetic_bag" --out "$bag" --frames 60 --seed 1 --malformed-every 10

rviz=false
[ "${RVIZ:-0}" = "1" ] && rviz=true
say "replaying it through the frame-by-frame detection viewer nodelet (roslaunch geofusion demo.launch)"
roslaunch --wait --skip-log-check geofusion demo.launch bag:="$bag" rviz:="$rviz" 2>&1 \
  | grep --line-buffered -v -e '^\s*$' -e 'started roslaunch server' -e 'setting /run_id' \
      -e 'process\[.*\]: started' -e 'ROS_MASTER_URI' -e '^\s*\*' -e 'SUMMARY' -e '=====' \
      -e 'PARAMETERS' -e 'NODES' -e '^  /' -e 'auto-starting new master' -e 'core service' \
      -e 'shutting down processing monitor' -e 'done$' -e 'boost::lock_error' || true
say "demo done: the summary line above says how many frames and detections the viewer used and skipped"
