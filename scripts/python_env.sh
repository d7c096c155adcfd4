#!/usr/bin/env bash
# Makes (or checks, in a second) the benchmark's Python environment: a venv over Debian's python3
# with its numpy and matplotlib, plus pycocotools (COCO mAP, the reference implementation) from
# PyPI, which Debian does not package.
set -euo pipefail
source "$(dirname "$0")/env.sh"
if "$GEOFUSION_VENV/bin/python" -c 'import pycocotools, matplotlib, numpy, yaml' 2>/dev/null; then
  exit 0
fi
say "making the benchmark's Python environment in $GEOFUSION_VENV (pycocotools from PyPI)"
/usr/bin/python3 -m venv --system-site-packages "$GEOFUSION_VENV"
# Pinned, and held to the numpy it sees (Debian's): pip must not bring a numpy that Debian's
# scipy and matplotlib were not built for (Debian 11: 1.19, 12: 1.24, 13: 2.2).
numpy_version=$(/usr/bin/python3 -c 'import numpy; print(numpy.__version__)')
"$GEOFUSION_VENV/bin/pip" install --quiet --disable-pip-version-check 'pycocotools==2.0.11' \
  "numpy==$numpy_version"
"$GEOFUSION_VENV/bin/python" -c 'import pycocotools, matplotlib, numpy, yaml'
