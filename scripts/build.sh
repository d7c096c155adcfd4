#!/usr/bin/env bash
# Builds the package, its tools and its tests in a catkin workspace outside the source tree.
set -euo pipefail
source "$(dirname "$0")/env.sh"

mkdir -p "$GEOFUSION_WS/src" "$ROS_HOME"
ln -sfn "$GEOFUSION_SRC" "$GEOFUSION_WS/src/geofusion"
cd "$GEOFUSION_WS"
# Extra CMake arguments, none by default (scripts/test_sanitizer.sh passes the sanitizer flags): shell
# words in GEOFUSION_CMAKE_ARGS, quotes allowed: -DCMAKE_BUILD_TYPE=Debug "-DCMAKE_CXX_FLAGS=-a -b".
mapfile -d '' -t EXTRA_CMAKE_ARGS < <(printf '%s' "${GEOFUSION_CMAKE_ARGS:-}" | xargs -r printf '%s\0')
say "building in $GEOFUSION_WS (catkin_make -j2$(command -v ccache >/dev/null && echo ', ccache'))"

set +u  # setup.bash reads unset variables
if [ ! -f build/.geofusion_configured ]; then
  # First build from empty: configure, build, then configure again with devel/setup.bash sourced
  # so that the cached test environment can import the generated Python messages.
  catkin_make -j2 "${CATKIN_PY_ARGS[@]}" -DCMAKE_BUILD_TYPE=Release "${EXTRA_CMAKE_ARGS[@]}"
  source devel/setup.bash
  catkin_make --force-cmake -j2 "${CATKIN_PY_ARGS[@]}" -DCMAKE_BUILD_TYPE=Release "${EXTRA_CMAKE_ARGS[@]}"
  touch build/.geofusion_configured
fi
source devel/setup.bash
# GEOFUSION_BUILD_TARGETS: what to build (default every target and the tests; make demo: all).
read -r -a targets <<< "${GEOFUSION_BUILD_TARGETS:-all tests}"
catkin_make -j2 "${CATKIN_PY_ARGS[@]}" "${EXTRA_CMAKE_ARGS[@]}" "${targets[@]}"
say "build done"
