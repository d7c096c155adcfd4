#!/usr/bin/env bash
# Installs everything GeoFusion needs to build, test and run, from Debian 12's own packages
# (ROS 1 "Debian" distro, PCL, Ceres, OpenCV, MRPT, OctoMap, FCL, OSMesa, ...).
# Idempotent: when everything is installed it only checks, in about a second, and exits.
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake ccache clang-format catkin-lint
  # ROS 1 from Debian: catkin, roscpp, rosbag, roslaunch, rostest, nodelet, tf2, messages, rviz
  ros-core rosbash libnodeletlib-dev libnodeletlib-tools python3-nodelet
  libtf2-eigen-dev python3-tf2-ros
  ros-sensor-msgs python3-sensor-msgs ros-nav-msgs libnav-msgs-dev python3-nav-msgs
  ros-visualization-msgs libvisualization-msgs-dev python3-visualization-msgs
  ros-std-srvs libstd-srvs-dev python3-std-srvs libcv-bridge-dev libimage-transport-dev
  libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure
  libroslib-dev librosbag-dev libtopic-tools-dev python3-rosbag librostest-dev python3-rostest libdiagnostic-updater-dev
  python3-diagnostic-msgs rviz librviz-dev
  # the core's libraries
  libeigen3-dev libceres-dev libpcl-conversions-dev libopencv-dev libmrpt-poses-dev libfcl-dev
  liboctomap-dev libqhull-dev libosmesa6-dev libmeshoptimizer-dev nlohmann-json3-dev libbullet-dev libassimp-dev libyaml-cpp-dev libgtest-dev
  # the Python module (docs/python.md)
  pybind11-dev python3-dev python3-pytest python3-pil
  # tools, tests, screenshots
  python3-numpy python3-scipy python3-yaml python3-matplotlib python3-venv python3-pip xvfb imagemagick
  liburdfdom-tools
  # package.xml's rosdep keys resolved offline (scripts/check_rosdep.sh)
  python3-rosdep2
)

# Per release: the Qt whose widgets rviz is built with (the map panel plugin links the same one;
# Debian 13's rviz 1.14.25 is built with Qt 6).
# (`--print RELEASE`: the list for that release, e.g. trixie; default: this machine's.)
codename=${2:-$(. /etc/os-release 2>/dev/null && echo "${VERSION_CODENAME:-}")}
case "$codename" in
  bullseye|bookworm|focal) PACKAGES+=(qtbase5-dev) ;;
  *) PACKAGES+=(qt6-base-dev) ;;
esac
# libsdformat (the exported SDF read back in the tests): Debian 13 packages none, and the test
# skips that part there (CMakeLists.txt).
case "$codename" in
  trixie) ;;
  *) PACKAGES+=(libsdformat-dev) ;;
esac


# --print [RELEASE]: the list, one name a line (scripts/test_platforms.sh installs the same list in its chroots).
if [ "${1:-}" = "--print" ]; then
  printf '%s\n' "${PACKAGES[@]}"
  exit 0
fi

installed=$(dpkg-query -W -f='${Package} ${db:Status-Abbrev}\n' "${PACKAGES[@]}" 2>/dev/null \
  | awk '$2 ~ /^ii/ {print $1}' || true)
missing=()
for p in "${PACKAGES[@]}"; do
  grep -qx "$p" <<<"$installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "[geofusion] dependencies: all ${#PACKAGES[@]} Debian packages are installed"
  exit 0
fi

SUDO=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "[geofusion] need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  SUDO=(sudo)
fi
echo "[geofusion] dependencies: installing ${#missing[@]} missing Debian package(s) (a first run takes a few minutes, about 2 GB):"
echo "  ${missing[*]}"
"${SUDO[@]}" apt-get update -q
# A private archive folder: some images delete /var/cache/apt/archives/*.deb after each apt run.
archives="${TMPDIR:-/tmp}/geofusion-apt-archives"
"${SUDO[@]}" mkdir -p "$archives/partial"
"${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
  -o Dir::Cache::archives="$archives" "${missing[@]}"
echo "[geofusion] dependencies: done"
