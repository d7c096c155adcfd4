// make_synthetic_bag: writes a small, self-contained recording of the analytic demo
// scene with the topics and frames of a Fetch robot (REP-103/105), and a ground-truth YAML beside
// it. Used by `make demo` and by the rostests; no model files needed.
//
//   make_synthetic_bag --out demo.bag [--ground-truth demo_gt.yaml] [--frames 60]
//       [--rate 10] [--seed 1] [--malformed-every 0] [--tf-until -1]
//       [--depth-encoding 32FC1|16UC1] [--detection-stamp-offset 0]
#include "command_line.h"
#include "geofusion/estimation/frame_by_frame.h"
#include "geofusion/ros/recording_writer.h"
#include "geofusion/simulation/box_scene.h"
#include "geofusion/simulation/sequence.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

namespace {

struct Options {
  std::string out;
  std::string ground_truth;
  int frames = 60;
  double rate_hz = 10.0;
  unsigned seed = 1;
  int malformed_every = 0;
  int tf_until = -1;
  std::string depth_encoding = "32FC1";
  double detection_stamp_offset_s = 0.0;
};

void usage() {
  std::cerr << "usage: make_synthetic_bag --out FILE.bag [--ground-truth FILE.yaml]\n"
               "         [--frames N=60] [--rate HZ=10] [--seed S=1] [--malformed-every K=0]\n"
               "         [--tf-until FRAME=-1] [--depth-encoding 32FC1|16UC1]\n"
               "         [--detection-stamp-offset SECONDS=0]\n";
}

Options parse(int argc, char** argv) {
  Options o;
  geofusion::CommandLine args;
  args.value("--out", &o.out);
  args.value("--ground-truth", &o.ground_truth);
  args.value("--frames", &o.frames);
  args.value("--rate", &o.rate_hz);
  args.value("--seed", &o.seed);
  args.value("--malformed-every", &o.malformed_every);
  args.value("--tf-until", &o.tf_until);
  args.value("--depth-encoding", &o.depth_encoding);
  args.value("--detection-stamp-offset", &o.detection_stamp_offset_s);
  args.parse(argc, argv, usage);
  if (o.out.empty()) throw std::runtime_error("--out is required");
  if (o.frames < 1 || o.rate_hz <= 0) throw std::runtime_error("--frames and --rate must be > 0");
  if (o.depth_encoding != "32FC1" && o.depth_encoding != "16UC1") {
    throw std::runtime_error("--depth-encoding must be 32FC1 or 16UC1");
  }
  if (o.ground_truth.empty()) {
    const auto dot = o.out.rfind(".bag");
    o.ground_truth = (dot == std::string::npos ? o.out : o.out.substr(0, dot)) + "_gt.yaml";
  }
  return o;
}

std::string vec(const Eigen::Vector3d& v) {
  char b[96];
  std::snprintf(b, sizeof(b), "[%.6f, %.6f, %.6f]", v.x(), v.y(), v.z());
  return b;
}

std::string quat(const Eigen::Matrix3d& R) {
  const Eigen::Quaterniond q(R);
  char b[128];
  std::snprintf(b, sizeof(b), "[%.9f, %.9f, %.9f, %.9f]", q.x(), q.y(), q.z(), q.w());
  return b;
}

// Detections the perception stack sometimes emits and the estimator must survive.
std::vector<geofusion::RawDetection> malformed() {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  geofusion::RawDetection base;
  base.class_name = "003_cracker_box";
  base.class_id = 2;
  base.score = 0.8;
  base.position_cam = Eigen::Vector3d(0.0, 0.0, 1.0);
  std::vector<geofusion::RawDetection> out(3, base);
  out[0].position_cam.y() = nan;                                // NaN translation
  out[1].orientation_cam = Eigen::Quaterniond(0, 0, 0, 0);      // zero quaternion
  out[2].orientation_cam = Eigen::Quaterniond(0.9, 0.9, 0, 0);  // non-unit quaternion
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  if (!geofusion::readCommandLine("make_synthetic_bag", usage, [&] { opt = parse(argc, argv); }))
    return 2;
  using namespace geofusion;
  const BoxScene scene = BoxScene::demoScene();
  const PinholeIntrinsics K;
  std::mt19937 rng(opt.seed);
  DetectionNoise noise;

  // Fetch-like head: camera 1.35 m above the floor, tilted down towards the table.
  Eigen::Isometry3d T_base_link = Eigen::Isometry3d::Identity();
  T_base_link.translation() = Eigen::Vector3d(0.05, 0.0, 1.35);
  T_base_link.linear() = Eigen::AngleAxisd(0.55, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Isometry3d T_link_optical = RobotGeometry::cameraLinkToOptical();

  RecordingLayout layout;
  layout.depth_encoding = opt.depth_encoding;
  RecordingWriter bag;
  std::string error;
  if (!bag.open(opt.out, layout, &error)) {
    std::cerr << "make_synthetic_bag: " << error << "\n";
    return 1;
  }
  std::ofstream gt(opt.ground_truth);
  if (!gt) {
    std::cerr << "make_synthetic_bag: cannot write " << opt.ground_truth << "\n";
    return 1;
  }

  const ros::Time t0(1600000000.0);
  bag.writeStaticTransforms(t0, T_link_optical, &T_base_link);

  gt << "# Ground truth of a make_synthetic_bag recording. Poses: position [x, y, z] m,\n"
        "# orientation [x, y, z, w]; world frame = odom (this recording has no drift).\n";
  gt << "frame_id: " << layout.odom_frame << "\ncamera_frame: " << layout.optical_frame << "\n";
  gt << "intrinsics: {width: " << K.width << ", height: " << K.height << ", fx: " << K.fx
     << ", fy: " << K.fy << ", cx: " << K.cx << ", cy: " << K.cy << "}\n";
  gt << "objects:\n";
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    const BoxObject& o = scene.objects[i];
    gt << "  - {index: " << i << ", class_name: " << o.class_name << ", class_id: " << o.class_id
       << ", size: " << vec(o.size) << ", position: " << vec(o.T_world_obj.translation())
       << ", orientation: " << quat(o.T_world_obj.linear()) << "}\n";
  }
  gt << "frames:\n";

  const FrameByFrame checker;  // to record which written detections are valid
  const double radius = 1.0, arc = 1.8;
  int total_detections = 0, total_malformed = 0;
  for (int k = 0; k < opt.frames; ++k) {
    const ros::Time stamp = t0 + ros::Duration(0.5 + k / opt.rate_hz);
    const double s = opt.frames > 1 ? static_cast<double>(k) / (opt.frames - 1) : 0.0;
    const double theta = M_PI - 0.5 * arc + arc * s;
    Eigen::Isometry3d T_odom_base = Eigen::Isometry3d::Identity();
    T_odom_base.translation() =
        Eigen::Vector3d(radius * std::cos(theta), radius * std::sin(theta), 0);
    T_odom_base.linear() =
        Eigen::AngleAxisd(theta + M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Isometry3d T_odom_cam = T_odom_base * T_base_link * T_link_optical;

    if (opt.tf_until < 0 || k <= opt.tf_until) bag.writeTransforms(stamp, T_odom_base);
    bag.writeOdometry(stamp, T_odom_base);
    const RenderedFrame frame = scene.render(K, T_odom_cam);
    bag.writeImages(stamp, K, frame.rgb, frame.depth);

    std::vector<RawDetection> dets = synthesizeDetections(scene, frame, T_odom_cam, noise, rng);
    const std::size_t num_valid = dets.size();
    if (opt.malformed_every > 0 && k % opt.malformed_every == 0) {
      for (const RawDetection& bad : malformed()) dets.push_back(bad);
    }
    bag.writeDetections(stamp + ros::Duration(opt.detection_stamp_offset_s), stamp, dets);
    total_detections += static_cast<int>(dets.size());
    total_malformed += static_cast<int>(dets.size() - num_valid);

    gt << "  - {index: " << k << ", stamp: " << std::fixed;
    gt.precision(9);
    gt << stamp.toSec() << ", camera_position: " << vec(T_odom_cam.translation())
       << ", camera_orientation: " << quat(T_odom_cam.linear())
       << ", tf: " << ((opt.tf_until < 0 || k <= opt.tf_until) ? "true" : "false")
       << ", malformed: " << (dets.size() - num_valid) << ", detections: [";
    for (std::size_t i = 0; i < num_valid; ++i) {
      ObjectMeasurement m;
      SkipReason reason;
      if (!checker.check(dets[i], &m, &reason)) continue;
      gt << (i ? ", " : "") << "{class_name: " << dets[i].class_name
         << ", world_position: " << vec(T_odom_cam * dets[i].position_cam) << "}";
    }
    gt << "]}\n";
    gt.unsetf(std::ios::fixed);
  }
  bag.close();
  std::cout << "make_synthetic_bag: wrote " << opt.frames << " frames (" << total_detections
            << " detections, " << total_malformed << " of them malformed) to " << opt.out
            << "; ground truth in " << opt.ground_truth << std::endl;
  return 0;
}
