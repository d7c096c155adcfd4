#!/usr/bin/env bash
# libFuzzer on GeoFusion's input parsers (test/fuzz/fuzz_*.cpp): the detection message conversion
# and checks, the model-set YAML loader, the parameter YAML loader, mesh loading and bag reading.
# Builds each target with clang++-14 -fsanitize=fuzzer,address,undefined (test/fuzz/CMakeLists.txt)
# in ~/.cache/geofusion/fuzz/build and runs it from the seed corpus test/fuzz/corpus/<target>/ and
# the regression inputs test/fuzz/regressions/<target>/. Exits 1 when a target found something:
# the input is in ~/.cache/geofusion/fuzz/artifacts/<target>/; once fixed, keep it in
# test/fuzz/regressions/<target>/ (test_fuzz_regressions runs those in every `make test`).
#   FUZZ_RUNS=N         executions per target (default 1000000)
#   FUZZ_MAX_TIME=S     and at most this many seconds per target (default 600)
#   FUZZ_TARGETS="..."  a subset of: detections vision_detections model_set config mesh bag
#   GEOFUSION_MSG_INCLUDE=DIR  a workspace's devel/include with the generated message headers
#                       (default: build the normal workspace with scripts/build.sh and use its own)
set -euo pipefail
source "$(dirname "$0")/env.sh"
runs="${FUZZ_RUNS:-1000000}"
max_time="${FUZZ_MAX_TIME:-600}"
read -r -a targets <<< "${FUZZ_TARGETS:-detections vision_detections model_set config mesh bag}"
root="${GEOFUSION_FUZZ_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/geofusion/fuzz}"
fuzz_src="$GEOFUSION_SRC/test/fuzz"

# clang 14 with libFuzzer and its sanitizer runtimes (Debian 12), installed when missing.
packages=(clang-14 libclang-rt-14-dev llvm-14)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${db:Status-Abbrev}' "$p" 2>/dev/null | grep -q '^ii' || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=()
  [ "$(id -u)" -eq 0 ] || SUDO=(sudo)
  say "fuzz: installing ${missing[*]}"
  "${SUDO[@]}" apt-get update -q
  archives="${TMPDIR:-/tmp}/geofusion-apt-archives"  # see install_deps.sh
  "${SUDO[@]}" mkdir -p "$archives/partial"
  "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
    -o Dir::Cache::archives="$archives" "${missing[@]}"
fi

# The generated message headers (geofusion/DetectionArray.h) come from a catkin build.
msg_include="${GEOFUSION_MSG_INCLUDE:-}"
if [ -z "$msg_include" ]; then
  bash "$GEOFUSION_SRC/scripts/install_deps.sh"
  bash "$GEOFUSION_SRC/scripts/build.sh"
  msg_include="$GEOFUSION_WS/devel/include"
fi

build="$root/build"
# A build folder configured from another checkout is started afresh.
if [ -f "$build/CMakeCache.txt" ] &&
   ! grep -qx "CMAKE_HOME_DIRECTORY:INTERNAL=$fuzz_src" "$build/CMakeCache.txt"; then
  rm -rf "$build"
fi
start=$(date +%s)
say "fuzz: building ${targets[*]} with clang++-14 in $build"
cmake -S "$fuzz_src" -B "$build" -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_BUILD_TYPE= \
  -DGEOFUSION_MSG_INCLUDE="$msg_include" "${CATKIN_PY_ARGS[@]}" > "$root.cmake.log" \
  || { cat "$root.cmake.log"; exit 1; }
cmake --build "$build" -j2 --target "${targets[@]/#/fuzz_}"
say "fuzz: build took $(( $(date +%s) - start )) s"

export ASAN_SYMBOLIZER_PATH=/usr/bin/llvm-symbolizer-14
export LSAN_OPTIONS="suppressions=$GEOFUSION_SRC/scripts/sanitizers/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
# mesh and bag feed their bytes mostly to assimp and rosbag (model_set its mesh files to assimp),
# which abort or over-allocate on corrupt files (scripts/sanitizers/fuzz_third_party.txt): those
# run in libFuzzer's fork mode, which goes on after a crash; every crash is then reproduced and
# sorted.
fork_targets=" model_set mesh bag "
known="$GEOFUSION_SRC/scripts/sanitizers/fuzz_third_party.txt"
known_re=$(grep -v -e '^#' -e '^ *$' "$known" | paste -sd '|')
# True when the crash report's first frame that is GeoFusion's or a known third party's is the
# latter.
third_party() {
  grep -E '^ *#[0-9]+ ' "$1" | grep -m1 -E "geofusion::|$known_re" | grep -qv 'geofusion::'
}
# The targets' scratch files (a crashing run leaves its folder behind): removed at the end.
export TMPDIR="$root/tmp"
rm -rf "$TMPDIR"
mkdir -p "$TMPDIR"
trap 'rm -rf "$TMPDIR"' EXIT
status=0
summary=()
for target in "${targets[@]}"; do
  corpus="$root/corpus/$target"        # what the fuzzer adds (kept between runs)
  artifacts="$root/artifacts/$target"
  log="$root/$target.log"
  mkdir -p "$corpus" "$artifacts"
  seeds=("$fuzz_src/corpus/$target")
  [ -d "$fuzz_src/regressions/$target" ] && seeds+=("$fuzz_src/regressions/$target")
  say "fuzz: $target: $runs runs, at most $max_time s (log $log)"
  t0=$(date +%s)
  mode=()
  [[ "$fork_targets" == *" $target "* ]] && mode=(-fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1)
  rm -f "$artifacts"/*
  result=0
  (cd "$root" && "$build/fuzz_$target" -runs="$runs" -max_total_time="$max_time" -timeout=30 \
    -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$artifacts/" "${mode[@]}" \
    "$corpus" "${seeds[@]}" \
    < /dev/null > "$log" 2>&1) || result=$?
  # Executions and their rate: the final stats, else (fork mode) the last status line.
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  last=$(grep -E '^#[0-9]+.*exec/s' "$log" | tail -1)
  [ -n "$execs" ] || execs=$(sed -E 's/^#([0-9]+).*/\1/' <<< "$last")
  [ -n "$rate" ] || rate=$(sed -nE 's/.*exec\/s:? ([0-9]+).*/\1/p' <<< "$last")
  seconds=$(( $(date +%s) - t0 ))
  [ -n "$rate" ] && [ "$rate" != 0 ] || rate=$(( ${execs:-0} / (seconds > 0 ? seconds : 1) ))
  line="$target: ${execs:-?} executions in $seconds s (${rate}/s)"
  findings=0 others=0
  for a in "$artifacts"/*; do
    [ -f "$a" ] || continue
    "$build/fuzz_$target" "$a" < /dev/null > "$a.report" 2>&1 || true
    if third_party "$a.report"; then
      others=$((others + 1))
    else
      findings=$((findings + 1))
      say "fuzz: $target: finding $a: $(grep -m1 -E '^==[0-9]+==ERROR|FUZZ_CHECK|runtime error|deadly signal|terminate called' "$a.report")"
      tail -40 "$a.report"
    fi
  done
  [ $others -eq 0 ] || line="$line, $others crash(es) in third-party code (reports in $artifacts)"
  if [ $findings -gt 0 ] || { [ $result -ne 0 ] && [ $others -eq 0 ]; }; then
    status=1
    line="$line, FOUND: $findings input(s) in $artifacts (exit $result)"
  else
    line="$line, no finding in GeoFusion"
  fi
  summary+=("$line")
done
say "fuzz: results"
printf '  %s\n' "${summary[@]}"
exit $status
