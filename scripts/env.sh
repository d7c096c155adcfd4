# Sourced by the other scripts: where the out-of-tree catkin workspace lives, and the environment
# that ROS 1 on Debian 12 needs.
GEOFUSION_SRC="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
# One workspace per clone, outside the source tree (override with GEOFUSION_WS).
_geofusion_id=$(printf '%s' "$GEOFUSION_SRC" | md5sum | cut -c1-8)
GEOFUSION_WS="${GEOFUSION_WS:-${XDG_CACHE_HOME:-$HOME/.cache}/geofusion/ws-$_geofusion_id}"
GEOFUSION_DATA="${GEOFUSION_DATA:-${XDG_CACHE_HOME:-$HOME/.cache}/geofusion/data}"
# Debian's ROS Python modules live in /usr/bin/python3's path, not in pyenv's python3.
export PATH="/usr/bin:$PATH"
export ROS_HOME="${ROS_HOME:-$GEOFUSION_WS/ros_home}"
CATKIN_PY_ARGS=(-DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3)
say() { echo "[geofusion] $*"; }
# The benchmark's Python: a venv over Debian's python3 (numpy, matplotlib, yaml from Debian) with
# pycocotools from PyPI (scripts/python_env.sh makes it).
GEOFUSION_VENV="${GEOFUSION_VENV:-${XDG_CACHE_HOME:-$HOME/.cache}/geofusion/venv}"
