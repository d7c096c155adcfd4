// vo_benchmark: runs the RGB-D visual odometry over a recording as fast as the machine allows
// (rosbag C++ API, no ROS master, OpenCV on one thread unless told otherwise) and measures it
// against the recording's ground truth: ATE RMSE after a rigid alignment, RPE over 1 s, time per
// frame, lost frames. Writes both trajectories in TUM format and the figures as JSON.
//
//   vo_benchmark --bag FILE.bag --ground-truth FILE_gt.yaml [--out-dir DIR] [--threads N]
//       [--params FILE] [--set visual_odometry.KEY=VALUE]... [--first-frame K] [--frame-step N]
//       [--rgb-topic T] [--depth-topic T] [--camera-info-topic T] [--quiet]
#include "command_line.h"
#include "config_option.h"
#include "geofusion/common/robot_names.h"
#include "geofusion/common/statistics.h"
#include "geofusion/evaluation/trajectory_metrics.h"
#include "geofusion/odometry/visual_odometry.h"
#include "geofusion/ros/conversions.h"
#include "geofusion/simulation/dataset.h"
#include "model_set_option.h"

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <vector>

namespace {

struct Options {
  std::string bag, ground_truth, out_dir = ".";
  std::string rgb_topic = std::string("/") + geofusion::kRgbTopic;
  std::string depth_topic = std::string("/") + geofusion::kDepthTopic;
  std::string info_topic = std::string("/") + geofusion::kCameraInfoTopic;
  int threads = 1;
  int first_frame = 0;  ///< image sets before this one are skipped
  int frame_step = 1;   ///< ... and then all but every N-th (a slower camera)
  bool quiet = false;
  geofusion::ConfigOptions config;  ///< --params, --set: the visual odometry's settings
};

void usage() {
  std::cerr << "usage: vo_benchmark --bag FILE.bag --ground-truth FILE_gt.yaml [--out-dir DIR]\n"
               "         [--threads N=1] [--params FILE] [--set visual_odometry.KEY=VALUE]...\n"
               "         [--first-frame K=0] [--frame-step N=1]\n"
               "         [--rgb-topic T] [--depth-topic T]\n"
               "         [--camera-info-topic T] [--quiet]\n";
}

Options parse(int argc, char** argv) {
  Options o;
  geofusion::CommandLine args;
  args.value("--bag", &o.bag);
  args.value("--ground-truth", &o.ground_truth);
  args.value("--out-dir", &o.out_dir);
  args.value("--threads", &o.threads);
  args.value("--first-frame", &o.first_frame);
  args.value("--frame-step", &o.frame_step);
  args.value("--rgb-topic", &o.rgb_topic);
  args.value("--depth-topic", &o.depth_topic);
  args.value("--camera-info-topic", &o.info_topic);
  args.toggle("--quiet", &o.quiet);
  o.config.declare(&args);
  args.parse(argc, argv, usage);
  if (o.bag.empty() || o.ground_truth.empty())
    throw std::runtime_error("--bag and --ground-truth are required");
  if (o.threads < 1) throw std::runtime_error("--threads must be at least 1");
  if (o.first_frame < 0) throw std::runtime_error("--first-frame must not be negative");
  if (o.frame_step < 1) throw std::runtime_error("--frame-step must be at least 1");
  return o;
}

/// One synchronised set of the recording.
struct Pending {
  sensor_msgs::ImageConstPtr rgb, depth;
  sensor_msgs::CameraInfoConstPtr info;
};

/// The odometry over the recording: the poses it tracked and its figures.
struct VoRun {
  explicit VoRun(const geofusion::VisualOdometryConfig& config) : vo(config) {}
  geofusion::VisualOdometry vo;
  std::vector<std::uint8_t> gray;  ///< the images converted, reused frame to frame
  std::vector<float> depth;
  geofusion::CameraRectifier camera;  ///< K and lens of camera_info (distorted images made pinhole)
  std::vector<double> stamps, times, convert_times;
  std::vector<Eigen::Isometry3d> poses;
  int frames = 0, lost = 0, by_depth = 0, restarts = 0, keyframes = 0, unusable = 0;
};

// One synchronised set through the odometry.
void trackFrame(const Options& opt, const Pending& set, VoRun* run, std::string* error) {
  using namespace geofusion;
  ++run->frames;
  // The node's own work before tracking: the grey and metric depth images.
  const auto c0 = std::chrono::steady_clock::now();
  const bool converted =
      odometryImages(*set.rgb, *set.depth, *set.info, &run->camera, &run->gray, &run->depth, error);
  run->convert_times.push_back(
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - c0).count());
  if (!converted) {
    ++run->unusable;
    return;
  }
  const PinholeIntrinsics& K = run->camera.K();
  GrayImageView g{run->gray.data(), static_cast<int>(set.rgb->width),
                  static_cast<int>(set.rgb->height), 0};
  DepthImageView d{run->depth.data(), static_cast<int>(set.depth->width),
                   static_cast<int>(set.depth->height)};
  const VoFrameResult r = run->vo.track(g, d, K, set.rgb->header.stamp.toSec());
  run->times.push_back(r.time_ms);
  run->keyframes += r.keyframe;
  if (r.restarted && run->frames > 1) ++run->restarts;
  if (!r.pose_valid) {
    ++run->lost;
    if (!opt.quiet)
      std::cerr << "vo_benchmark: frame " << run->frames << " lost: " << r.problem << " ("
                << r.features << " features, " << r.features_with_depth << " with depth, "
                << r.matches << " matches)\n";
    return;
  }
  if (r.by_depth) {
    ++run->by_depth;
    if (!opt.quiet)
      std::cerr << "vo_benchmark: frame " << run->frames << " placed by its depth in " << r.time_ms
                << " ms (features: " << r.problem << ")\n";
  }
  run->stamps.push_back(set.rgb->header.stamp.toSec());
  run->poses.push_back(r.T_odom_cam);
}

// The recording's images and camera info, made into sets by their stamps, through the odometry.
void runOdometry(const Options& opt, const rosbag::Bag& bag, VoRun* run, std::string* error) {
  std::map<uint64_t, Pending> pending;
  int index = 0;  // of the image set in the recording
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{opt.rgb_topic, opt.depth_topic,
                                                                     opt.info_topic}));
  for (const rosbag::MessageInstance& m : view) {
    uint64_t stamp = 0;
    if (m.getTopic() == opt.info_topic) {
      auto msg = m.instantiate<sensor_msgs::CameraInfo>();
      if (!msg) continue;
      stamp = msg->header.stamp.toNSec();
      pending[stamp].info = msg;
    } else {
      auto msg = m.instantiate<sensor_msgs::Image>();
      if (!msg) continue;
      stamp = msg->header.stamp.toNSec();
      (m.getTopic() == opt.rgb_topic ? pending[stamp].rgb : pending[stamp].depth) = msg;
    }
    Pending& p = pending[stamp];
    if (!p.rgb || !p.depth || !p.info) continue;
    const Pending set = p;
    pending.erase(pending.begin(), pending.upper_bound(stamp));
    const int i = index++;
    if (i < opt.first_frame || (i - opt.first_frame) % opt.frame_step != 0) continue;
    trackFrame(opt, set, run, error);
  }
}

nlohmann::json resultsJson(const Options& opt, const geofusion::GeoFusionConfig& config,
                           const geofusion::GroundTruth& gt, const VoRun& run,
                           const geofusion::TrajectoryErrors& e) {
  using namespace geofusion;
  nlohmann::json j;
  j["format"] = "geofusion_vo_benchmark_v1";
  j["scene"] = gt.scene_name;
  j["suite"] = gt.suite;
  j["bag"] = opt.bag;
  j["frames"] = run.frames;
  j["unusable_frames"] = run.unusable;
  j["lost_frames"] = run.lost;
  j["depth_frames"] = run.by_depth;
  j["restarts"] = run.restarts;
  j["keyframes"] = run.keyframes;
  j["paired_poses"] = e.pairs;
  j["path_length_m"] = e.length_m;
  j["ate_rmse_m"] = e.ate_rmse_m;
  j["ate_mean_m"] = e.ate_mean_m;
  j["ate_max_m"] = e.ate_max_m;
  j["rpe_delta_s"] = e.rpe_delta_s;
  j["rpe_translation_rmse_m"] = e.rpe_translation_rmse_m;
  j["rpe_rotation_rmse_deg"] = e.rpe_rotation_rmse_deg;
  j["time_ms_median"] = percentile(run.times, 0.5);
  j["convert_ms_median"] = percentile(run.convert_times, 0.5);
  j["time_ms_p95"] = percentile(run.times, 0.95);
  j["time_ms_max"] = percentile(run.times, 1.0);
  j["opencv_threads"] = opt.threads;
  j["first_frame"] = opt.first_frame;
  j["frame_step"] = opt.frame_step;
  j["config"] = configYaml(config, false, false, {"visual_odometry"});
  j["config_changed"] = configDiff(config);
  return j;
}

void printSummary(const Options& opt, const geofusion::GroundTruth& gt, const VoRun& run,
                  const geofusion::TrajectoryErrors& e, const std::string& stem) {
  using namespace geofusion;
  std::printf(
      "vo_benchmark: %s: %d frames (%d lost, %d by depth, %d restarts, %d keyframes), path %.2f "
      "m; ATE RMSE "
      "%.2f cm (mean %.2f, max %.2f); RPE over 1 s %.2f cm, %.2f deg; time per frame median "
      "%.1f ms, p95 %.1f ms (%d OpenCV thread%s; image conversion %.1f ms more); %s_vo.tum, "
      "%s_vo.json\n",
      gt.scene_name.c_str(), run.frames, run.lost, run.by_depth, run.restarts, run.keyframes,
      e.length_m, 100 * e.ate_rmse_m, 100 * e.ate_mean_m, 100 * e.ate_max_m,
      100 * e.rpe_translation_rmse_m, e.rpe_rotation_rmse_deg, percentile(run.times, 0.5),
      percentile(run.times, 0.95), opt.threads, opt.threads == 1 ? "" : "s",
      percentile(run.convert_times, 0.5), stem.c_str(), stem.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  using namespace geofusion;
  Options opt;
  if (!geofusion::readCommandLine("vo_benchmark", usage, [&] { opt = parse(argc, argv); }))
    return 2;
  cv::setNumThreads(opt.threads);
  GeoFusionConfig config;
  if (!opt.config.apply("vo_benchmark", &config)) return 2;
  GroundTruth gt;
  std::string error;
  // Only the camera trajectory is used, but reading the file resolves its classes: the model
  // set it names (YCB-Video meshes from $GEOFUSION_YCB_DIR or ../shared, as evaluate_run).
  ModelSet models;
  if (!loadModelSetOption("vo_benchmark", modelSetOf(opt.ground_truth), "", &models)) return 1;
  if (!readGroundTruth(opt.ground_truth, models, &gt, &error)) {
    std::cerr << "vo_benchmark: " << error << "\n";
    return 1;
  }
  rosbag::Bag bag;
  try {
    bag.open(opt.bag, rosbag::bagmode::Read);
  } catch (const std::exception& e) {
    std::cerr << "vo_benchmark: cannot read " << opt.bag << ": " << e.what() << "\n";
    return 1;
  }
  VoRun run(config.visual_odometry);
  runOdometry(opt, bag, &run, &error);
  std::vector<double> true_stamps;
  std::vector<Eigen::Isometry3d> truth;
  for (const GroundTruthFrame& f : gt.frames) {
    true_stamps.push_back(f.stamp_s);
    truth.push_back(f.T_map_optical);
  }
  const TrajectoryErrors e = trajectoryErrors(run.stamps, run.poses, true_stamps, truth, 1.0);

  std::filesystem::create_directories(opt.out_dir);
  const std::string stem = opt.out_dir + "/" + gt.scene_name;
  if (!writeTum(stem + "_vo.tum", run.stamps, run.poses, &error) ||
      !writeTum(stem + "_truth.tum", true_stamps, truth, &error)) {
    std::cerr << "vo_benchmark: " << error << "\n";
    return 1;
  }
  std::ofstream(stem + "_vo.json") << resultsJson(opt, config, gt, run, e).dump(2) << "\n";
  printSummary(opt, gt, run, e, stem);
  return 0;
}
