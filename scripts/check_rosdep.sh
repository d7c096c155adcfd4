#!/usr/bin/env bash
# Resolves every rosdep key of package.xml (its REP 149 conditions evaluated for Noetic) for
# ubuntu:focal + noetic, offline, with Debian's python3-rosdep2 reading the ROS distribution
# index and rosdep rules kept in ../shared/platforms/rosdistro (no network). Exit 1 naming every
# key that does not resolve. Usage: check_rosdep.sh [PACKAGE_DIR] [ROSDISTRO_DIR]
#   ROSDEP_OS (default ubuntu:focal), ROSDEP_DISTRO (default noetic)
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd -P)"
pkg="${1:-$here}"
rosdistro="${2:-${GEOFUSION_ROSDISTRO_DIR:-$here/../shared/platforms/rosdistro}}"
if [ ! -d "$rosdistro" ]; then
  echo "check_rosdep: SKIPPED, no rosdistro files at $rosdistro (set GEOFUSION_ROSDISTRO_DIR)"
  exit 77
fi
rosdistro="$(cd "$rosdistro" && pwd -P)"
os="${ROSDEP_OS:-ubuntu:focal}"
distro="${ROSDEP_DISTRO:-noetic}"
export PATH="/usr/bin:$PATH"
command -v rosdep >/dev/null || { echo "check_rosdep: rosdep not found (python3-rosdep2)" >&2; exit 1; }
for f in index-v4.yaml rosdep/base.yaml rosdep/python.yaml "$distro/distribution.yaml"; do
  [ -f "$rosdistro/$f" ] || { echo "check_rosdep: $rosdistro/$f missing" >&2; exit 1; }
done

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/sources.list.d"
printf 'yaml file://%s/rosdep/base.yaml\nyaml file://%s/rosdep/python.yaml\n' "$rosdistro" "$rosdistro" \
  > "$tmp/sources.list.d/20-default.list"
export ROSDEP_SOURCE_PATH="$tmp/sources.list.d" ROSDISTRO_INDEX_URL="file://$rosdistro/index-v4.yaml"
export ROS_HOME="$tmp/ros" ROS_DISTRO="$distro" ROS_VERSION=1 ROS_PYTHON_VERSION=3
rosdep update --rosdistro "$distro" --include-eol-distros >"$tmp/update.log" 2>&1 \
  || { cat "$tmp/update.log" >&2; echo "check_rosdep: rosdep update failed" >&2; exit 1; }

# The package's keys with its conditions evaluated for $distro (rosdep keys reads the environment).
mkdir -p "$tmp/src/geofusion"
cp "$pkg/package.xml" "$tmp/src/geofusion/"
mapfile -t keys < <(rosdep keys --from-paths "$tmp/src" --rosdistro "$distro" | sort -u)
[ ${#keys[@]} -gt 0 ] || { echo "check_rosdep: no keys read from $pkg/package.xml" >&2; exit 1; }
# All keys in one call (rosdep loads its database once); key by key only when that fails, to name
# every key that does not resolve.
if out=$(rosdep resolve "${keys[@]}" --os "$os" --rosdistro "$distro" 2>&1); then
  awk '/^#ROSDEP\[/ {key = substr($0, 9, length($0) - 9); next} /^#/ {next}
       {printf "  %-24s -> %s\n", key, $0}' <<<"$out"
  echo "check_rosdep: all ${#keys[@]} keys of package.xml resolve for $os + $distro"
  exit 0
fi
failed=()
for key in "${keys[@]}"; do
  if out=$(rosdep resolve "$key" --os "$os" --rosdistro "$distro" 2>&1); then
    printf '  %-24s -> %s\n' "$key" "$(grep -v '^#' <<<"$out" | tr '\n' ' ')"
  else
    printf '  %-24s DOES NOT RESOLVE: %s\n' "$key" "$(tr '\n' ' ' <<<"$out")"
    failed+=("$key")
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "check_rosdep: ${#failed[@]} of ${#keys[@]} keys do not resolve for $os + $distro: ${failed[*]}" >&2
  exit 1
fi
echo "check_rosdep: all ${#keys[@]} keys of package.xml resolve for $os + $distro"
