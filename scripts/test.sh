#!/usr/bin/env bash
# Runs the whole test suite (lint, core gtests, rostests) through ctest; exits non-zero on failure.
set -euo pipefail
source "$(dirname "$0")/env.sh"

set +u
source "$GEOFUSION_WS/devel/setup.bash"
set -u
bash "$GEOFUSION_SRC/scripts/python_env.sh"  # pycocotools for the benchmark tests
cd "$GEOFUSION_WS/build"
say "ctest: lint, core unit tests (gtest, no ROS master) and rostests (replayed bags)"
ctest --output-on-failure
