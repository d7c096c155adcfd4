#!/usr/bin/env bash
# The libraries and executables that run on the robot link no simulation or evaluation code and
# none of their libraries (Bullet, nlohmann_json's users): `ldd` on each, a failure names what
# leaked in. Usage: check_runtime_links.sh FILE...
set -euo pipefail
forbidden='libgeofusion_simulation|libgeofusion_evaluation|libBullet|libLinearMath'
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
