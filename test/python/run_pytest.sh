#!/usr/bin/env bash
# pytest on the given files (ctest python_module). Under scripts/test_sanitizer.sh the sanitizer
# runtimes are preloaded (GEOFUSION_SANITIZER_PRELOAD): python3 is not instrumented, the
# geofusion.core it imports is, and ASan must come first in the process.
set -euo pipefail
if [ -n "${GEOFUSION_SANITIZER_PRELOAD:-}" ]; then
  export LD_PRELOAD="$GEOFUSION_SANITIZER_PRELOAD${LD_PRELOAD:+:$LD_PRELOAD}"
  export ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0"  # the interpreter's own, at its exit
fi
exec /usr/bin/python3 -m pytest -q -p no:cacheprovider "$@"
