#!/usr/bin/env bash
# catkin_lint on the package and clang-format (the repository's .clang-format) on every C++ file.
set -euo pipefail
source "$(dirname "$0")/env.sh"
cd "$GEOFUSION_SRC"
# Lint the workspace link: catkin_lint wants the folder named like the package.
catkin_lint --strict -W2 "$GEOFUSION_WS/src/geofusion"
mapfile -t files < <(git ls-files '*.h' '*.cpp' 2>/dev/null || find include src test -name '*.h' -o -name '*.cpp')
if [ ${#files[@]} -gt 0 ]; then
  clang-format --dry-run -Werror "${files[@]}"
fi
say "lint clean (${#files[@]} C++ files)"
