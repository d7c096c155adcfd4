#!/usr/bin/env bash
# The demo: generates the demo scene (built-in primitive models, a Fetch-like recording with its
# ground truth), runs GeoFusion on it with the offline runner, and prints what it found against
# the ground truth. Files land in $GEOFUSION_DATA/demo.
set -euo pipefail
source "$(dirname "$0")/env.sh"
set +u
source "$GEOFUSION_WS/devel/setup.bash"
set -u
out="$GEOFUSION_DATA/demo"
bin="$GEOFUSION_WS/devel/lib/geofusion"
say "generating the demo scene (cached after the first run): $out"
"$bin/generate_dataset" --suite demo --out-dir "$out" | grep -E "demo_01|generated"
say "running GeoFusion on $out/demo_01.bag (run_offline)"
"$bin/run_offline" --bag "$out/demo_01.bag" --out "$out/demo_01_geofusion.yaml" --method geofusion \
  --background "$out/demo_01_background.bt"
say "what it found against the ground truth:"
/usr/bin/python3 "$GEOFUSION_SRC/src/tools/evaluate_run.py" --results "$out/demo_01_geofusion.yaml" \
  --ground-truth "$out/demo_01_gt.yaml"
say "the map (objects, contacts, trajectory, timings): $out/demo_01_geofusion.yaml"
say "the static background (OctoMap, objects removed): $out/demo_01_background.bt"
say "frames of the recording as PNG: $out/previews/"
