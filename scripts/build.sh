#!/usr/bin/env bash
# Builds the package, its tools and its tests in a catkin workspace outside the source tree.
set -euo pipefail
source "$(dirname "$0")/env.sh"

mkdir -p "$GEOFUSION_WS/src" "$ROS_HOME"
ln -sfn "$GEOFUSION_SRC" "$GEOFUSION_WS/src/geofusion"
cd "$GEOFUSION_WS"
say "building in $GEOFUSION_WS (catkin_make -j2$(command -v ccache >/dev/null && echo ', ccache'))"

set +u  # setup.bash reads unset variables
if [ ! -f build/.geofusion_configured ]; then
  # First build from empty: configure, build, then configure again with devel/setup.bash sourced
  # so that the cached test environment can import the generated Python messages.
  catkin_make -j2 "${CATKIN_PY_ARGS[@]}" -DCMAKE_BUILD_TYPE=Release
  source devel/setup.bash
  catkin_make --force-cmake -j2 "${CATKIN_PY_ARGS[@]}" -DCMAKE_BUILD_TYPE=Release
  touch build/.geofusion_configured
fi
source devel/setup.bash
catkin_make -j2 "${CATKIN_PY_ARGS[@]}" all tests
say "build done"
