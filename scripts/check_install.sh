#!/usr/bin/env bash
# The package works from an install space with nothing of the source tree: installs the built
# workspace into its install space (`catkin_make install`: the prefix catkin configured, whose
# setup files it writes), checks that no installed program has the source path compiled
# in, then from the install space alone checks the configuration template, generates a small
# demo recording, runs GeoFusion over it with the installed template and evaluates the run, and
# resolves the installed launch files. Usage: check_install.sh CATKIN_BUILD_DIR SOURCE_DIR
set -euo pipefail
build="$1"
src_given="${2%/}"
src="$(cd "$2" && pwd -P)"
prefix="$(sed -n 's/^CMAKE_INSTALL_PREFIX:PATH=//p' "$build/CMakeCache.txt")"
work="$(mktemp -d /tmp/geofusion_install_run_XXXXXX)"
trap 'rm -rf "$work"' EXIT
say() { echo "check_install: $*"; }

case "$prefix" in
  */install) rm -rf "$prefix" ;;
  *) say "unexpected install prefix '$prefix'"; exit 1 ;;
esac
cmake --install "$build" > "$work/install.log"
say "installed into $prefix ($(find "$prefix" -type f | wc -l) files)"
for f in "$prefix"/lib/geofusion/* "$prefix"/lib/libgeofusion_*.so; do
  [ -f "$f" ] && [ -x "$f" ] || continue
  # The source path as a string of its own (a compiled-in directory) or followed by a data folder;
  # log locations (__FILE__, the path of a .cpp) are not read and do not count.
  if ! python3 - "$f" "$src_given" "$src" <<'PY'
import re, sys
data = open(sys.argv[1], 'rb').read()
for path in set(sys.argv[2:]):
    p = re.escape(path.encode())
    if re.search(p + rb'(\x00|/config|/\.\.|/launch|/rviz)', data):
        sys.exit(1)
PY
  then
    say "$(basename "$f") reads from the source tree"; exit 1
  fi
done
say "no installed program reads from the source tree"

# From here on only the install space: a fresh environment without the devel space.
env -i HOME="$HOME" PATH=/usr/bin:/bin ROS_HOME="$work/ros" \
    GEOFUSION_SANITIZER_PRELOAD="${GEOFUSION_SANITIZER_PRELOAD:-}" bash -c '
  set -euo pipefail
  prefix="$1"; work="$2"
  set +u; source "$prefix/setup.bash"; set -u
  cd "$work"
  share="$(rospack find geofusion)"
  [ "$share" = "$prefix/share/geofusion" ] || { echo "check_install: rospack finds $share"; exit 1; }
  bin="$prefix/lib/geofusion"
  "$bin/geofusion_params" check "$share/config/scene_estimator.yaml" | tail -1
  "$bin/generate_dataset" --suite demo --out-dir "$work/data" --keyframes 12 --previews 0 > gen.log
  "$bin/run_offline" --bag "$work/data/demo_01.bag" --out "$work/run.yaml" \
      --params "$share/config/scene_estimator.yaml" --quiet
  "$bin/evaluate_run" --ground-truth "$work/data/demo_01_gt.yaml" --results "$work/run.yaml" \
      --json "$work/eval.json" --quiet
  python3 -c "import json, sys; e = json.load(open(sys.argv[1])); \
assert e[\"final_map\"][\"matched\"] > 0, e[\"final_map\"]; \
assert e[\"config\"][\"method\"] == \"geofusion\"; \
print(\"check_install: run from the install space: %d objects matched, config recorded\" % e[\"final_map\"][\"matched\"])" "$work/eval.json"
  # The Python module from the install space, with the installed configuration template (under
  # scripts/test_sanitizer.sh with the sanitizer runtimes preloaded: the interpreter is not instrumented).
  LD_PRELOAD="$GEOFUSION_SANITIZER_PRELOAD" ASAN_OPTIONS=detect_leaks=0 /usr/bin/python3 -c "import sys, geofusion.core as gf; \
assert gf.__file__.startswith(sys.argv[1]), gf.__file__; \
e = gf.SceneEstimator(gf.load_model_set(), sys.argv[2]); \
print(\"check_install: geofusion.core from %s, method %s\" % (gf.__file__, e.method))" \
      "$prefix" "$share/config/scene_estimator.yaml"
  for f in geofusion.launch fetch.launch visual_odometry.launch detection_viewer.launch; do
    roslaunch --files geofusion "$f" > /dev/null
  done
  roslaunch --files geofusion replay.launch bag:=/dev/null > /dev/null
  echo "check_install: the installed launch files resolve"
' _ "$prefix" "$work"
