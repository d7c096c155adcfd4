#!/usr/bin/env bash
# Generates a named data suite (SUITE=demo or bench) into $GEOFUSION_DATA/<suite> (cached: scenes
# already made with the same settings are kept), then checks every bag with the validator.
# DATA_ARGS passes more options to generate_dataset (e.g. "--detector posecnn --force").
set -euo pipefail
source "$(dirname "$0")/env.sh"
set +u
source "$GEOFUSION_WS/devel/setup.bash"
set -u
suite="${SUITE:-demo}"
out="$GEOFUSION_DATA/$suite"
say "generating suite '$suite' into $out"
# shellcheck disable=SC2086
"$GEOFUSION_WS/devel/lib/geofusion/generate_dataset" --suite "$suite" --out-dir "$out" ${DATA_ARGS:-}
for bag in "$out"/*.bag; do
  /usr/bin/python3 "$GEOFUSION_SRC/src/tools/validate_bag.py" "$bag" | grep '^SUMMARY'
done
say "suite '$suite' ready in $out (ground truth: <scene>_gt.yaml; previews in $out/previews)"
