#!/usr/bin/env bash
# catkin_lint on the package and clang-format (the repository's .clang-format) on every C++ file.
# The formatting is checked with the clang-format the project formats with (major version
# GEOFUSION_CLANG_FORMAT_MAJOR, 14: Debian 12's): other versions format some constructs
# differently (19 on Debian 13 changes 2 files), so with no clang-format 14 on the machine
# (clang-format-14 or a clang-format that reports 14) the formatting check is skipped and says so.
set -euo pipefail
source "$(dirname "$0")/env.sh"
cd "$GEOFUSION_SRC"
# Lint the workspace link: catkin_lint wants the folder named like the package.
# Dependencies are rosdep keys, checked by scripts/check_rosdep.sh (ctest rosdep_keys); without a
# rosdep database catkin_lint 1.6.9 (Debian 11) calls each one unknown, later versions skip them.
catkin_lint --strict -W2 --ignore unknown_package "$GEOFUSION_WS/src/geofusion"
mapfile -t files < <(git ls-files '*.h' '*.cpp' 2>/dev/null || find include src test -name '*.h' -o -name '*.cpp')
want="${GEOFUSION_CLANG_FORMAT_MAJOR:-14}"
formatter=""
for candidate in "clang-format-$want" clang-format; do
  command -v "$candidate" >/dev/null || continue
  major=$("$candidate" --version | sed -n 's/.*clang-format version \([0-9]*\).*/\1/p')
  if [ "$major" = "$want" ]; then formatter="$candidate"; break; fi
done
if [ -z "$formatter" ]; then
  say "clang-format $want not found ($(clang-format --version 2>/dev/null || echo 'no clang-format')):" \
      "formatting check SKIPPED, catkin_lint done"
elif [ ${#files[@]} -gt 0 ]; then
  "$formatter" --dry-run -Werror "${files[@]}"
  say "lint clean (${#files[@]} C++ files, $formatter $want)"
fi
