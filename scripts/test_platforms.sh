#!/usr/bin/env bash
# make test-platforms: builds and tests the package as a ROS user would on other Debian releases,
# one release at a time, each in a minimal chroot (docs/tests.md "Other platforms"):
#   1. mmdebstrap makes the chroot from the Debian source this machine's apt already uses (read
#      here at run time), with the package list of scripts/install_deps.sh (the same names exist
#      on Debian 11 to 13) and the release's extras (Debian 11: gcc-9 and CMake 3.16.3 from PyPI,
#      Ubuntu 20.04's toolchain). The chroot is kept and reused; packages the list gained since
#      are installed into it.
#   2. The tracked files of this tree are copied into a fresh catkin workspace's src/geofusion.
#   3. catkin_make builds it (configure, source devel/setup.bash, configure again, all + tests),
#      then ctest runs every test there, with ../shared's models and real frames bind-mounted.
#   4. catkin build (catkin-tools) builds the same workspace again (catkin_make's spaces moved
#      aside, so that the compiler cache serves it) and ctest runs the gtests, the Python module,
#      the install space and the estimator's rostest from its build space.
# Profiles: bullseye, bookworm, trixie (Debian releases as they are) and focal: Ubuntu 20.04's
# differences on Debian 11 (gcc-9 and CMake 3.16.3 as bullseye, and also Ubuntu 20.04's own
# pybind11-dev 2.4.3 in place of Debian's 2.6, no meshoptimizer). PyPI's pybind11 2.4.3 (wheel and
# sdist) has the headers only, no CMake config, so the focal profile installs Ubuntu's package
# (checked against its SHA-256 below).
# Usage: scripts/test_platforms.sh RELEASE...   (bullseye | focal | bookworm | trixie; default: bullseye focal trixie)
# Needs root (mmdebstrap, mount, chroot). Environment: GEOFUSION_CHROOT_DIR (default
# ~/.cache/geofusion/chroots), GEOFUSION_SHARED (default ../shared beside the source tree),
# CTEST_ARGS (extra ctest arguments, e.g. "-R test_core"), GEOFUSION_REUSE_BUILD=1 (run the tests
# again in the workspace the last run built, without copying or building).
set -euo pipefail
source "$(dirname "$0")/env.sh"

[ "$(id -u)" -eq 0 ] || { echo "[geofusion] test-platforms needs root (chroot, mount)" >&2; exit 1; }
command -v mmdebstrap >/dev/null || {
  say "installing mmdebstrap"
  apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends mmdebstrap
}

chroots="${GEOFUSION_CHROOT_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/geofusion/chroots}"
shared="${GEOFUSION_SHARED:-$GEOFUSION_SRC/../shared}"

# The Debian source apt uses here: the first URIs of a deb822 file, else the first deb line.
debian_source() {
  local uri
  uri=$(cat /etc/apt/sources.list.d/*.sources 2>/dev/null | awk '/^URIs:/ {print $2}' \
        | grep -v -- '-security' | head -n1 || true)
  if [ -z "$uri" ]; then
    uri=$(cat /etc/apt/sources.list /etc/apt/sources.list.d/*.list 2>/dev/null \
          | awk '$1 == "deb" && $0 !~ /security/ {for (i = 2; i <= NF; i++) if ($i ~ /^[a-z]+:\/\//) {print $i; exit}}')
  fi
  [ -n "$uri" ] || { echo "[geofusion] no Debian source found in /etc/apt" >&2; exit 1; }
  echo "$uri"
}

# The Debian release a profile's chroot is made from.
base_release() {
  case "$1" in
    focal) echo bullseye ;;
    bullseye|bookworm|trixie) echo "$1" ;;
    *) echo "[geofusion] unknown profile '$1' (bullseye, focal, bookworm or trixie)" >&2; exit 1 ;;
  esac
}

# Packages beyond scripts/install_deps.sh's list. catkin-tools is packaged from Debian 12 on; on
# Debian 11 it comes from PyPI (inside_script), as Ubuntu 20.04 users get it from ROS's archive.
release_extras() {
  case "$1" in
    bullseye|focal) echo "gcc-9 g++-9" ;;  # Ubuntu 20.04's compiler (CMake 3.16.3 comes from PyPI)
    bookworm|trixie) echo "catkin-tools" ;;
    *) base_release "$1" >/dev/null ;;
  esac
}

# Packages of install_deps.sh's list a profile goes without (focal: Ubuntu 20.04 has no
# meshoptimizer; its pybind11 is Ubuntu's 2.4.3, installed by install_profile_packages).
release_without() {
  case "$1" in
    focal) echo "libmeshoptimizer-dev pybind11-dev" ;;
    *) echo "" ;;
  esac
}

package_list() {
  local profile="$1" p skip
  skip=" $(release_without "$profile") "
  for p in $(bash "$GEOFUSION_SRC/scripts/install_deps.sh" --print "$(base_release "$profile")") $(release_extras "$profile"); do
    [[ "$skip" == *" $p "* ]] || echo "$p"
  done | tr '\n' ' '
}

# focal: Ubuntu 20.04's pybind11-dev (headers and CMake config, architecture all, no dependencies).
UBUNTU_PYBIND11_DEB=http://archive.ubuntu.com/ubuntu/pool/universe/p/pybind11/pybind11-dev_2.4.3-2build2_all.deb
UBUNTU_PYBIND11_SHA256=019b8891d021be15b087c3df71ddad0b4531fc566e7b7e2b1f809a4c791b105e
install_profile_packages() {
  local profile="$1" dir="$2" deb
  [ "$profile" = focal ] || return 0
  if chroot "$dir" dpkg-query -W -f='${Version}' pybind11-dev 2>/dev/null | grep -q '^2\.4\.3'; then
    return 0
  fi
  deb="$dir/tmp/$(basename "$UBUNTU_PYBIND11_DEB")"
  say "focal: installing Ubuntu 20.04's pybind11-dev 2.4.3 ($UBUNTU_PYBIND11_DEB)"
  curl -fsSL -o "$deb" "$UBUNTU_PYBIND11_DEB"
  echo "$UBUNTU_PYBIND11_SHA256  $deb" | sha256sum -c --quiet -
  chroot "$dir" dpkg -i "/tmp/$(basename "$deb")"
  rm -f "$deb"
}

make_chroot() {
  local profile="$1" dir="$2" release list mirror start
  release=$(base_release "$profile")
  list=$(package_list "$profile")
  if [ -f "$dir/.geofusion-release" ]; then
    # Kept from an earlier run: only what the list gained since is installed.
    say "$release: reusing the chroot $dir"
    chroot "$dir" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin DEBIAN_FRONTEND=noninteractive \
      bash -c "dpkg-query -W -f='\${Package} \${db:Status-Abbrev}\n' $list 2>/dev/null | awk '\$2 ~ /^ii/ {print \$1}' | sort > /tmp/have
               missing=\$(for p in $list; do grep -qx \"\$p\" /tmp/have || echo \$p; done)
               if [ -n \"\$missing\" ]; then
                 echo \"[geofusion] $release: installing\" \$missing
                 apt-get update -q && apt-get install -y -q --no-install-recommends \$missing
               fi"
    install_profile_packages "$profile" "$dir"
    return
  fi
  mirror=$(debian_source)
  say "$profile: making a minimal $release chroot in $dir from $mirror ($(wc -w <<<"$list") packages)"
  rm -rf "$dir"
  mkdir -p "$chroots"  # mmdebstrap makes $dir, not its parent (a fresh machine has none)
  start=$(date +%s)
  mmdebstrap --variant=apt --components=main --include="$(tr -s ' ' ',' <<<"$list" | sed 's/^,//; s/,$//')" \
    "$release" "$dir" "deb $mirror $release main" "deb $mirror $release-updates main"
  install_profile_packages "$profile" "$dir"
  echo "$profile" > "$dir/.geofusion-release"
  say "$profile: chroot made from $release in $(( $(date +%s) - start )) s"
}

mount_chroot() {
  local dir="$1"
  mount -t proc proc "$dir/proc"
  mount --rbind /sys "$dir/sys" && mount --make-rslave "$dir/sys"
  mount --rbind /dev "$dir/dev" && mount --make-rslave "$dir/dev"
  mkdir -p "$dir/shared" "$dir/ccache"
  if [ -d "$shared" ]; then mount --bind -o ro "$shared" "$dir/shared"; fi
  # One compiler cache per Debian release (focal's objects are mostly bullseye's).
  local cache="$chroots/ccache-$(base_release "$(basename "$dir")")"
  mkdir -p "$cache"
  mount --bind "$cache" "$dir/ccache"
  cp /etc/resolv.conf "$dir/etc/resolv.conf" 2>/dev/null || true
  # roslaunch resolves localhost and the machine's name: a minimal chroot has no /etc/hosts.
  cp /etc/hosts "$dir/etc/hosts" 2>/dev/null || printf '127.0.0.1 localhost\n::1 localhost\n' > "$dir/etc/hosts"
  # This machine's trust (a proxy's certificate authority among them) for pip inside.
  if [ -f /etc/ssl/certs/ca-certificates.crt ]; then
    mkdir -p "$dir/etc/ssl/certs"
    cp /etc/ssl/certs/ca-certificates.crt "$dir/etc/ssl/certs/ca-certificates.crt"
  fi
  if [ -f /etc/pip.conf ]; then cp /etc/pip.conf "$dir/etc/pip.conf"; fi
}

unmount_chroot() {
  local dir="$1" m
  for m in ccache shared dev sys proc; do
    umount -R -l "$dir/$m" 2>/dev/null || true
  done
}

# What runs inside: the workspace's build and tests, as a ROS user runs them: catkin_make and every
# test, then catkin build and the tests of CATKIN_TOOLS_TESTS (the same binaries, another tool).
inside_script() {
  cat <<'INSIDE'
set -euo pipefail
export HOME=/root LANG=C.UTF-8 CCACHE_DIR=/ccache ROS_HOSTNAME=localhost
export GEOFUSION_WS=/ws GEOFUSION_YCB_DIR=/shared/data/ycb_video GEOFUSION_REAL_DIR=/shared/data/real
export GEOFUSION_ROSDISTRO_DIR=/shared/platforms/rosdistro
case "$RELEASE" in
  bullseye|focal)
    # Ubuntu 20.04's toolchain: GCC 9 and CMake 3.16.3.
    # (its venv's python3 stays off PATH: only cmake, ctest and cpack are linked).
    if [ ! -x /opt/cmake-3.16/venv/bin/cmake ]; then
      python3 -m venv /opt/cmake-3.16/venv && /opt/cmake-3.16/venv/bin/pip install --quiet 'cmake==3.16.3.post1'
    fi
    mkdir -p /opt/cmake-3.16/bin
    for tool in cmake ctest cpack; do ln -sfn /opt/cmake-3.16/venv/bin/$tool /opt/cmake-3.16/bin/$tool; done
    export PATH=/opt/cmake-3.16/bin:$PATH CC=gcc-9 CXX=g++-9
    # catkin-tools: not packaged by Debian 11; ROS's Noetic archive has 0.9.4, PyPI the same.
    if ! command -v catkin >/dev/null; then
      python3 -m venv --system-site-packages /opt/catkin-tools/venv
      /opt/catkin-tools/venv/bin/pip install --quiet 'catkin-tools==0.9.4'
      ln -sfn /opt/catkin-tools/venv/bin/catkin /usr/local/bin/catkin
    fi
    ;;
esac
echo "[geofusion] $RELEASE: $(cmake --version | head -n1), $(${CXX:-c++} --version | head -n1), $(python3 --version), numpy $(python3 -c 'import numpy; print(numpy.__version__)'), $(catkin --version | head -n1)"
# The environment before any setup.bash: catkin build starts from it.
mapfile -d '' -t clean_env < <(env -0)
args=(-DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 -DCMAKE_BUILD_TYPE=Release)
cd /ws
if [ "$REUSE_BUILD" = 1 ]; then
  echo "[geofusion] $RELEASE: the workspace built before, tests only"
else
  rm -rf /ws/.catkin_tools /ws/build /ws/devel /ws/install /ws/logs
  start=$(date +%s)
  set +u
  catkin_make -j2 "${args[@]}"
  source devel/setup.bash
  catkin_make --force-cmake -j2 "${args[@]}"
  catkin_make -j2 "${args[@]}" all tests
  set -u
  echo "[geofusion] $RELEASE: catkin_make took $(( $(date +%s) - start )) s"
fi
bash /ws/src/geofusion/scripts/python_env.sh
run_ctest() {  # label, ctest arguments; runs in the package's build folder (catkin_make's or catkin build's)
  local label="$1" start=$(date +%s) status=0
  shift
  ( set +u; source /ws/devel/setup.bash; set -u
    cd /ws/build/geofusion && ctest --output-on-failure "$@" ) || status=$?
  echo "[geofusion] $RELEASE: $label: tests took $(( $(date +%s) - start )) s, ctest exit $status"
  return $status
}
status=0
run_ctest "$( [ -d /ws/.catkin_tools ] && echo 'catkin build' || echo catkin_make )" $CTEST_ARGS || status=$?
if [ "$REUSE_BUILD" != 1 ] && [ "$status" -eq 0 ] && [ -z "$CTEST_ARGS" ]; then
  # catkin build on the same sources. catkin_make's spaces are removed first, so that catkin
  # build's build/geofusion and merged devel space have the very paths catkin_make's had and the
  # compiler cache serves it; the environment is the one before any setup.bash. The second build
  # configures again (--force-cmake), as catkin_make's second run does: catkin's cached test
  # environment (env_cached.sh) is written at configure time and only lists devel folders that
  # exist then, so the first configure's has no Python path and the rostests' checkers cannot
  # import geofusion.msg.
  rm -rf /ws/build /ws/devel /ws/install
  start=$(date +%s)
  env -i "${clean_env[@]}" bash -c '
    set -euo pipefail
    cd /ws && catkin init >/dev/null
    catkin config --merge-devel --cmake-args "$@" >/dev/null
    catkin build --no-status --summarize -j2
    catkin build --no-status --summarize -j2 --force-cmake --make-args tests' catkin-build "${args[@]}"
  echo "[geofusion] $RELEASE: catkin build took $(( $(date +%s) - start )) s"
  run_ctest "catkin build" -R "$CATKIN_TOOLS_TESTS" || status=$?
fi
exit $status
INSIDE
}

test_release() {
  local release="$1" dir="$chroots/$1" status=0
  release_extras "$release" >/dev/null
  make_chroot "$release" "$dir"
  if [ "${GEOFUSION_REUSE_BUILD:-0}" != 1 ]; then
    rm -rf "$dir/ws" && mkdir -p "$dir/ws/src/geofusion"
    (cd "$GEOFUSION_SRC" && git ls-files -co --exclude-standard -z | tar --null -T - -cf -) \
      | tar -xf - -C "$dir/ws/src/geofusion"
    say "$release: $(cd "$GEOFUSION_SRC" && git describe --always --dirty) copied into $dir/ws/src/geofusion"
  fi
  # The demo recording this machine made (if any), so that every release maps the same frames
  # and bench_demo's reports compare (Bullet and the compilers settle generated scenes a little
  # differently on each release).
  rm -rf "$dir/root/.cache/geofusion/data/demo"
  if [ -d "$GEOFUSION_DATA/demo" ]; then
    mkdir -p "$dir/root/.cache/geofusion/data" && cp -a "$GEOFUSION_DATA/demo" "$dir/root/.cache/geofusion/data/"
    say "$release: the demo recording of $GEOFUSION_DATA/demo copied in"
  fi
  trap 'unmount_chroot "'"$dir"'"' EXIT
  mount_chroot "$dir"
  local pass=() v
  for v in http_proxy https_proxy no_proxy HTTP_PROXY HTTPS_PROXY NO_PROXY PIP_INDEX_URL; do
    [ -n "${!v:-}" ] && pass+=("$v=${!v}")
  done
  [ -f /etc/ssl/certs/ca-certificates.crt ] && pass+=(SSL_CERT_FILE=/etc/ssl/certs/ca-certificates.crt
    PIP_CERT=/etc/ssl/certs/ca-certificates.crt REQUESTS_CA_BUNDLE=/etc/ssl/certs/ca-certificates.crt)
  # The script as a file, stdin empty: a test reading stdin must not eat the script's lines.
  inside_script > "$dir/geofusion-inside.sh"
  chroot "$dir" /usr/bin/env -i PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
    RELEASE="$release" CTEST_ARGS="${CTEST_ARGS:-}" REUSE_BUILD="${GEOFUSION_REUSE_BUILD:-0}" \
    CATKIN_TOOLS_TESTS="$catkin_tools_tests" "${pass[@]}" \
    bash /geofusion-inside.sh </dev/null || status=$?
  unmount_chroot "$dir"
  trap - EXIT
  if [ -f "$dir/ws/build/geofusion/bench_demo/report.md" ]; then
    cp "$dir/ws/build/geofusion/bench_demo/report.md" "$chroots/$release-bench_demo.md"
    say "$release: bench_demo's report kept in $chroots/$release-bench_demo.md"
  fi
  say "$release: $([ $status -eq 0 ] && echo PASSED || echo "FAILED (exit $status)")"
  return $status
}

# What catkin build's workspace runs: the gtests, the Python module, the install space and the
# estimator's rostest (the rest would run the same binaries again).
catkin_tools_tests='gtest_test_core$|gtest_test_ros_layer$|^python_module$|^install_space$|rostest_test_ros_scene_estimator\.test$'
releases=("$@")
[ ${#releases[@]} -gt 0 ] || releases=(bullseye focal trixie)
failed=()
for r in "${releases[@]}"; do
  # Each release in a job of its own, so that `set -e` holds inside it (bash ignores it in a
  # function called as `test_release || ...`): a release stops at its first failed step (a chroot
  # that could not be made is never entered) and the next release still runs.
  test_release "$r" &
  wait $! || failed+=("$r")
done
if [ ${#failed[@]} -gt 0 ]; then
  say "test-platforms: FAILED on ${failed[*]}"
  exit 1
fi
say "test-platforms: passed on ${releases[*]}"
