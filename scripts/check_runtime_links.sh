#!/usr/bin/env bash
# The libraries and executables that run on the robot link no simulation or evaluation code:
# `ldd` on each, a failure names what leaked in. (Bullet is a runtime library since issue 50: the
# stability check, geofusion_physics, runs in run_offline's summary and the estimator.)
# Usage: check_runtime_links.sh FILE...
set -euo pipefail
forbidden='libgeofusion_simulation|libgeofusion_evaluation'
status=0
for f in "$@"; do
  if [ ! -e "$f" ]; then
    echo "check_runtime_links: $f does not exist (build it first)"; status=1; continue
  fi
  leaked=$(ldd "$f" | grep -E "$forbidden" | awk '{print $1}' | tr '\n' ' ' || true)
  if [ -n "$leaked" ]; then
    echo "check_runtime_links: $(basename "$f") links offline-only libraries: $leaked"; status=1
  else
    echo "check_runtime_links: $(basename "$f"): $(ldd "$f" | grep -c libgeofusion_) geofusion libraries, none offline-only"
  fi
done
exit $status
