#!/usr/bin/env bash
# The commented templates in config/ are what `geofusion_params template` prints today: a setting
# added, renamed or re-documented in the loader shows up here until the templates are regenerated
# (`bash scripts/check_config_templates.sh TOOL --write`).
set -euo pipefail
tool="$1"
mode="${2:-check}"
src="$(cd "$(dirname "$0")/.." && pwd)"
status=0
while read -r file name sections; do
  # shellcheck disable=SC2086
  generated=$("$tool" template "$name" $sections)
  if [ "$mode" = --write ]; then
    printf '%s\n' "$generated" > "$src/config/$file"
    echo "check_config_templates: wrote config/$file"
  elif ! diff -u "$src/config/$file" <(printf '%s\n' "$generated"); then
    echo "check_config_templates: config/$file is stale (regenerate with --write)"
    status=1
  else
    echo "check_config_templates: config/$file matches the loader"
  fi
done <<'LIST'
scene_estimator.yaml scene_estimator method model_set input keyframes consistency refinement monitor association lifecycle stage_one relations stage_two physics scene_graph background node
visual_odometry.yaml visual_odometry input visual_odometry
detection_viewer.yaml detection_viewer input
LIST
exit $status
