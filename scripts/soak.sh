#!/usr/bin/env bash
# make soak (issue 22): GeoFusion on a long generated run (tables visited in turn and revisited),
# time and memory per keyframe into results/soak/soak.csv, plotted to results/soak/*.png.
#   SOAK_KEYFRAMES=2000  keyframes        SOAK_ARGS="..."  more soak_benchmark options
set -euo pipefail
source "$(dirname "$0")/env.sh"
set +u
source "$GEOFUSION_WS/devel/setup.bash"
set -u
out="$GEOFUSION_SRC/results/soak"
mkdir -p "$out"
say "soak: ${SOAK_KEYFRAMES:-2000} keyframes into $out"
# shellcheck disable=SC2086
"$GEOFUSION_WS/devel/lib/geofusion/soak_benchmark" --keyframes "${SOAK_KEYFRAMES:-2000}" \
  --out "$out/soak.csv" ${SOAK_ARGS:-} | tee "$out/soak.txt"
/usr/bin/python3 "$GEOFUSION_SRC/bench/plot_soak.py" "$out/soak.csv" "$out"
say "soak: summary in $out/soak.txt, plots $out/soak_time.png and $out/soak_memory.png"
