#!/usr/bin/env python3
"""Checks the module layout (docs/architecture.md): every #include of a geofusion header goes along
the stated direction of dependency, ROS headers appear only in the ROS layer and the tools, and
the heavy libraries' headers (PCL, FCL, Ceres, OpenCV, Bullet, OctoMap, OSMesa) stay out of the
modules' public headers. Exit status 1 with one line per violation.

  check_modules.py [ROOT]     check the package at ROOT (default: this script's package)
  check_modules.py --self-test  check that violations planted in a scratch tree are caught
"""
import os
import re
import shutil
import sys
import tempfile

RUNTIME = ["common", "model", "physics", "render", "estimation", "odometry", "background", "config"]
# module -> modules its files may include (itself included).
ALLOWED = {
    "common": {"common"},
    "model": {"common", "model"},
    "physics": {"common", "model", "physics"},
    "render": {"common", "model", "render"},
    "estimation": {"common", "model", "physics", "render", "estimation"},
    "odometry": {"common", "odometry"},
    "background": {"common", "model", "render", "background"},
    "config": {"common", "model", "physics", "render", "estimation", "odometry", "background",
               "config"},
    "simulation": set(RUNTIME) | {"simulation"},
    "evaluation": set(RUNTIME) | {"simulation", "evaluation"},
    "ros": set(RUNTIME) | {"ros"},
    "python": set(RUNTIME) | {"python"},
}
# Folders of files that belong to a module, as (path prefix, module). Tools, benchmarks and tests
# may include any module (tests make their inputs with the simulation); only the ROS rule holds
# for them.
FOLDERS = [("include/geofusion/%s/" % m, m) for m in ALLOWED] + \
          [("src/%s/" % m, m) for m in ALLOWED] + \
          [("src/nodes/", "ros"), ("src/rviz/", "ros")]
ROS_FOLDERS = ("include/geofusion/ros/", "src/ros/", "src/nodes/", "src/rviz/", "src/tools/",
               "test/ros/", "test/fuzz/")

GEOFUSION_INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]geofusion/([a-z_]+)/[^>"]+[>"]')
ROS_INCLUDE = re.compile(
    r'^\s*#\s*include\s*[<"](ros|nodelet|pluginlib|tf2|tf2_ros|tf2_eigen|tf2_msgs|sensor_msgs|'
    r'geometry_msgs|nav_msgs|std_msgs|std_srvs|visualization_msgs|diagnostic_msgs|rosbag|'
    r'cv_bridge|image_transport|message_filters|dynamic_reconfigure|diagnostic_updater|'
    r'octomap_msgs|vision_msgs)/')
GENERATED_MESSAGE = re.compile(r'^\s*#\s*include\s*[<"]geofusion/[A-Z][A-Za-z]*\.h[>"]')
HEAVY_INCLUDE = re.compile(
    r'^\s*#\s*include\s*<(pcl/|fcl/|ceres/|opencv2/|btBullet|octomap/|GL/|assimp/|mrpt/|libqhull)')
# Public headers meant for a few .cpp files only, which may bring a heavy library.
HEAVY_ALLOWED = {"include/geofusion/model/fcl_hull.h", "include/geofusion/common/ceres_compat.h"}


def module_of(rel):
    for prefix, module in FOLDERS:
        if rel.startswith(prefix):
            return module
    return None


def check(root):
    problems = []
    for top in ("include", "src", "test", "bench"):
        for dirpath, _, files in os.walk(os.path.join(root, top)):
            for name in sorted(files):
                if not name.endswith((".h", ".hpp", ".cpp", ".cc")):
                    continue
                path = os.path.join(dirpath, name)
                rel = os.path.relpath(path, root).replace(os.sep, "/")
                problems += check_file(path, rel)
    return problems


def check_file(path, rel):
    problems = []
    module = module_of(rel)
    with open(path, encoding="utf-8", errors="replace") as f:
        lines = f.readlines()
    for number, line in enumerate(lines, 1):
        where = "%s:%d" % (rel, number)
        m = GEOFUSION_INCLUDE.match(line)
        if m and module is not None:
            target = m.group(1)
            if target not in ALLOWED:
                problems.append("%s: includes unknown module '%s'" % (where, target))
            elif target not in ALLOWED[module]:
                problems.append("%s: module '%s' includes '%s' against the direction of "
                                "dependency (allowed: %s)" %
                                (where, module, target, ", ".join(sorted(ALLOWED[module]))))
        if (ROS_INCLUDE.match(line) or GENERATED_MESSAGE.match(line)) and \
                not rel.startswith(ROS_FOLDERS):
            problems.append("%s: ROS header outside the ROS layer and the tools: %s" %
                            (where, line.strip()))
        if rel.startswith("include/geofusion/") and module in RUNTIME + ["simulation", "evaluation"] \
                and HEAVY_INCLUDE.match(line) and rel not in HEAVY_ALLOWED:
            problems.append("%s: heavy library header in a public header (move it to the .cpp): "
                            "%s" % (where, line.strip()))
    return problems


def self_test():
    """Plants one violation of each kind in a copy of the layout and checks each is reported."""
    scratch = tempfile.mkdtemp(prefix="check_modules_")
    try:
        def write(rel, text):
            path = os.path.join(scratch, rel)
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, "w") as f:
                f.write(text)
        write("include/geofusion/common/ok.h", '#include "geofusion/common/camera.h"\n')
        write("src/estimation/ok.cpp", '#include "geofusion/render/renderer.h"\n')
        write("src/tools/ok.cpp", '#include "geofusion/evaluation/metrics.h"\n#include <ros/ros.h>\n')
        clean = check(scratch)
        if clean:
            print("self-test: a clean tree was reported:\n  " + "\n  ".join(clean))
            return 1
        write("src/estimation/bad.cpp", '#include "geofusion/simulation/clutter_scene.h"\n')
        write("include/geofusion/odometry/bad.h", '#include "geofusion/render/consistency.h"\n')
        write("src/model/bad_ros.cpp", '#include <sensor_msgs/Image.h>\n')
        write("include/geofusion/render/bad_heavy.h", '#include <opencv2/core.hpp>\n')
        found = check(scratch)
        expected = ["src/estimation/bad.cpp:1", "include/geofusion/odometry/bad.h:1",
                    "src/model/bad_ros.cpp:1", "include/geofusion/render/bad_heavy.h:1"]
        missed = [e for e in expected if not any(p.startswith(e) for p in found)]
        if missed or len(found) != len(expected):
            print("self-test: expected %s, got:\n  %s" % (expected, "\n  ".join(found)))
            return 1
        print("check_modules self-test: %d planted violations caught, clean tree passes" %
              len(expected))
        return 0
    finally:
        shutil.rmtree(scratch)


def main(argv):
    if len(argv) > 1 and argv[1] == "--self-test":
        return self_test()
    root = argv[1] if len(argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    problems = check(root)
    for p in problems:
        print(p)
    if problems:
        print("check_modules: %d violation(s) of the module layout (docs/architecture.md)" %
              len(problems))
        return 1
    print("check_modules: every include follows the module layout")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
