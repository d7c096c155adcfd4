# GeoFusion: the two commands a user needs.
#   make demo   install what is missing, build (not the tests), and run the demo
#   make test   install what is missing, build, and run every test (exit code = result)
#   make data SUITE=demo|bench|bench_rgb   generate (or reuse) a data suite in ~/.cache/geofusion/data
#   make bench [SUITE=demo]      the benchmark: four methods, report in results/<suite>/
#   make bench-real              every method on the real frames of ../shared/data/real, the visual
#                                odometry beside Open3D's and OpenCV's; report in results/real/
#   make live-bench              the robot's launch fed by rosbag play at 1x and 2x, idle and loaded:
#                                latency frame -> map, drops, CPU; report in results/live/
#   make vo-bench                the visual odometry benchmark, report in results/vo/
#   make test-asan               every test built with ASan + UBSan in its own workspace, run by ctest
#   make test-tsan               the same with ThreadSanitizer (its own workspace; docs/tests.md)
#   make fuzz [FUZZ_RUNS=N]      libFuzzer (clang 14) on the input parsers, 1000000 runs per target
#   make screenshots             the rviz screenshots of README and docs/running.md (docs/images) by the rviz_screenshots test
#   make soak [SOAK_KEYFRAMES=N] a long run (tables revisited): time and memory per keyframe, plots
#   make test-platforms [RELEASES="bullseye focal trixie"]  build + every test in Debian 11 / 13 chroots
#                                (focal: Ubuntu 20.04's pybind11, no meshoptimizer; catkin_make and catkin build; root; docs/tests.md)
.PHONY: demo test test-asan test-tsan fuzz data bench bench-real live-bench vo-bench screenshots soak test-platforms deps build lint clean help

help:
	@sed -n '2,17p' Makefile

deps:
	@bash scripts/install_deps.sh

build: deps
	@bash scripts/build.sh

test: build
	@bash scripts/test.sh

test-asan:
	@bash scripts/test_sanitizer.sh address

test-tsan:
	@bash scripts/test_sanitizer.sh thread

fuzz:
	@bash scripts/fuzz.sh

demo: deps
	@GEOFUSION_BUILD_TARGETS=all bash scripts/build.sh
	@bash scripts/demo.sh

data: build
	@bash scripts/data.sh

bench: build
	@bash scripts/bench.sh

bench-real: build
	@bash scripts/bench_real.sh

live-bench: build
	@bash scripts/live_bench.sh

vo-bench: build
	@bash scripts/vo_bench.sh

soak: build
	@bash scripts/soak.sh

screenshots: build
	@bash -c 'source scripts/env.sh && set +u && source "$$GEOFUSION_WS/devel/setup.bash" && GEOFUSION_SCREENSHOT_DIR=$(CURDIR)/docs/images /usr/bin/python3 test/ros/rviz_screenshots.py'

RELEASES ?= bullseye focal trixie
test-platforms:
	@bash scripts/test_platforms.sh $(RELEASES)

lint:
	@bash scripts/lint.sh

clean:
	@bash -c 'source scripts/env.sh && echo "[geofusion] removing $$GEOFUSION_WS" && rm -rf "$$GEOFUSION_WS"'
