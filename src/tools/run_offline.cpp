// run_offline: runs the scene estimator over a recording as fast as the machine allows (rosbag
// C++ API, no ROS master) and writes a results file (docs/results.md).
//
//   run_offline --bag FILE.bag --out results.yaml [--params FILE.yaml] [--set KEY=VALUE]...
//       [--method geofusion|fbf|fbfr|bslam|rfront] [--model-set primitives|ycb_video|FILE.yaml]
//       [--models DIR] [--keyframe-every N]
//       [--depth-topic T] [--camera-info-topic T] [--detections-topic T] [--odom-frame odom]
//       [--background FILE.bt] [--quiet]
//   run_offline [--params FILE.yaml] [--set KEY=VALUE]... --print-params
// The configuration is the nodes' (config/config.h): the file of --params, then --set and the
// shorthands (--method = method, --model-set = model_set.name, --models = model_set.dir,
// --keyframe-every = keyframes.every_n_frames) in the order given; it is written into the
// results.
#include "command_line.h"
#include "geofusion/common/robot_names.h"
#include "geofusion/config/config.h"
#include "geofusion/estimation/run_results.h"
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/ros/estimator_pipeline.h"
#include "model_set_option.h"

#include <geofusion/DetectionArray.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2/buffer_core.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <string>

namespace {

struct Options {
  std::string bag, out;
  std::string params;  ///< the configuration file
  /// (key, value) overrides in the order given: --set and the shorthands.
  std::vector<std::pair<std::string, std::string>> overrides;
  bool print_params = false;
  std::string depth_topic = std::string("/") + geofusion::kDepthTopic;
  std::string info_topic = std::string("/") + geofusion::kCameraInfoTopic;
  std::string detections_topic = std::string("/") + geofusion::kDetectionsTopic;
  std::string odom_frame = geofusion::kOdomFrame;
  std::string background;  ///< .bt file of the background OctoMap; empty: none
  bool quiet = false;
};

void usage() {
  std::cerr << "usage: run_offline --bag FILE.bag --out RESULTS.yaml [--params FILE.yaml]\n"
               "         [--set KEY=VALUE]... [--method geofusion|fbf|fbfr|bslam|rfront]\n"
               "         [--model-set primitives|ycb_video|FILE.yaml] [--models DIR]\n"
               "         [--keyframe-every N] [--depth-topic T] [--camera-info-topic T]\n"
               "         [--detections-topic T] [--odom-frame odom] [--background FILE.bt]\n"
               "         [--quiet]\n"
               "       run_offline [--params FILE.yaml] [--set KEY=VALUE]... --print-params\n";
}

Options parse(int argc, char** argv) {
  Options o;
  geofusion::CommandLine args;
  args.value("--bag", &o.bag);
  args.value("--out", &o.out);
  args.value("--params", &o.params);
  auto shorthand = [&](const std::string& flag, const std::string& key) {
    args.custom(flag, [&o, key](const std::string& v) { o.overrides.emplace_back(key, v); });
  };
  shorthand("--method", "method");
  shorthand("--model-set", "model_set.name");
  shorthand("--models", "model_set.dir");
  shorthand("--keyframe-every", "keyframes.every_n_frames");
  args.custom("--set", [&o](const std::string& v) {
    const std::size_t eq = v.find('=');
    if (eq == std::string::npos) throw std::runtime_error("--set expects KEY=VALUE, got " + v);
    o.overrides.emplace_back(v.substr(0, eq), v.substr(eq + 1));
  });
  args.toggle("--print-params", &o.print_params);
  args.value("--depth-topic", &o.depth_topic);
  args.value("--camera-info-topic", &o.info_topic);
  args.value("--detections-topic", &o.detections_topic);
  args.value("--odom-frame", &o.odom_frame);
  args.value("--background", &o.background);
  args.toggle("--quiet", &o.quiet);
  args.parse(argc, argv, usage);
  if (!o.print_params && (o.bag.empty() || o.out.empty()))
    throw std::runtime_error("--bag and --out are required");
  return o;
}

// The configuration of the options: the file, then the overrides; every problem on stderr.
bool configure(const Options& o, geofusion::GeoFusionConfig* config) {
  geofusion::ConfigReport report;
  if (!o.params.empty()) geofusion::loadConfigFile(o.params, config, &report);
  for (const auto& [key, value] : o.overrides) {
    std::string error;
    if (!geofusion::setConfigValue(key, value, config, &error))
      report.errors.push_back("command line: " + error);
  }
  for (const std::string& w : report.warnings) std::cerr << "run_offline: warning: " << w << "\n";
  for (const std::string& e : report.errors) std::cerr << "run_offline: " << e << "\n";
  return report.ok();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace geofusion;
  Options opt;
  try {
    opt = parse(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "run_offline: " << e.what() << "\n";
    usage();
    return 2;
  }
  GeoFusionConfig config;
  if (!configure(opt, &config)) return 2;
  if (opt.print_params) {
    std::cout << configYaml(config);
    return 0;
  }
  if (!opt.quiet)
    std::cerr << "run_offline: configuration (differences from the defaults):\n"
              << configDiff(config) << "\n";
  const Method method = config.estimator.method;
  ModelSet models;
  if (!loadModelSetOption("run_offline", config.model_set.name, config.model_set.dir, &models,
                          config.model_set.surface_features))
    return 1;

  rosbag::Bag bag;
  try {
    bag.open(opt.bag, rosbag::bagmode::Read);
  } catch (const std::exception& e) {
    std::cerr << "run_offline: cannot read " << opt.bag << ": " << e.what() << "\n";
    return 1;
  }
  const auto start = std::chrono::steady_clock::now();
  // TF of the whole recording first (an offline run may look anywhere in time).
  rosbag::View all(bag);
  const double duration = (all.getEndTime() - all.getBeginTime()).toSec();
  tf2::BufferCore tf(ros::Duration(std::max(10.0, duration + 10.0)));
  for (const rosbag::MessageInstance& m :
       rosbag::View(bag, rosbag::TopicQuery(std::vector<std::string>{"/tf", "/tf_static"}))) {
    const auto msg = m.instantiate<tf2_msgs::TFMessage>();
    if (!msg) continue;
    const bool is_static = m.getTopic() == "/tf_static";
    for (const auto& t : msg->transforms) {
      try {
        tf.setTransform(t, "bag", is_static);
      } catch (const std::exception&) {
      }
    }
  }

  const BackgroundMapConfig& background_config = config.background;
  EstimatorPipeline pipeline(models, config.estimator, config.keyframes, config.checks,
                             opt.background.empty() ? nullptr : &background_config);
  RunResults results;
  results.method = toString(method);
  results.config_yaml = configYaml(config);
  results.source = opt.bag;
  results.model_set = models.name();
  results.recording_duration_s = duration;

  // Sets of depth, camera_info and detections with the same header stamp.
  struct Pending {
    sensor_msgs::ImageConstPtr depth;
    sensor_msgs::CameraInfoConstPtr info;
    geofusion::DetectionArrayConstPtr detections;
  };
  std::map<uint64_t, Pending> pending;
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{
                             opt.depth_topic, opt.info_topic, opt.detections_topic}));
  const std::size_t total = view.size();
  std::size_t read = 0;
  int warned = 0;
  for (const rosbag::MessageInstance& m : view) {
    ++read;
    uint64_t stamp = 0;
    if (m.getTopic() == opt.depth_topic) {
      auto msg = m.instantiate<sensor_msgs::Image>();
      if (!msg) continue;
      stamp = msg->header.stamp.toNSec();
      pending[stamp].depth = msg;
    } else if (m.getTopic() == opt.info_topic) {
      auto msg = m.instantiate<sensor_msgs::CameraInfo>();
      if (!msg) continue;
      stamp = msg->header.stamp.toNSec();
      pending[stamp].info = msg;
    } else {
      auto msg = m.instantiate<geofusion::DetectionArray>();
      if (!msg) continue;
      stamp = msg->header.stamp.toNSec();
      pending[stamp].detections = msg;
    }
    Pending& p = pending[stamp];
    if (!p.depth || !p.info || !p.detections) continue;
    const Pending set = p;
    pending.erase(stamp);
    // Older incomplete sets will not complete any more.
    pending.erase(pending.begin(), pending.lower_bound(stamp));
    ++results.frames_seen;
    Eigen::Isometry3d T_odom_cam;
    try {
      T_odom_cam = tf2::transformToEigen(tf.lookupTransform(
          opt.odom_frame, set.detections->header.frame_id, set.detections->header.stamp));
    } catch (const std::exception& e) {
      ++results.frames_skipped;
      if (warned++ < 5) std::cerr << "run_offline: frame skipped, no TF: " << e.what() << "\n";
      continue;
    }
    KeyframeResult r;
    const auto outcome = pipeline.process(*set.depth, *set.info, *set.detections, T_odom_cam, &r);
    if (outcome == EstimatorPipeline::Outcome::kBadDepth) {
      ++results.frames_skipped;
      if (warned++ < 5) std::cerr << "run_offline: frame skipped: unusable depth image\n";
      continue;
    }
    if (outcome != EstimatorPipeline::Outcome::kKeyframe) continue;
    results.keyframes.push_back(r);
    if (!opt.quiet && results.keyframes.size() % 10 == 0) {
      const int percent = static_cast<int>(100.0 * read / std::max<std::size_t>(1, total));
      std::fprintf(stderr, "\r[%-40s] %3d%%  %zu keyframes, %zu objects",
                   std::string(percent * 40 / 100, '#').c_str(), percent, results.keyframes.size(),
                   results.keyframes.back().objects.size());
    }
  }
  results.final_map = pipeline.estimator().finish();
  results.trajectory = pipeline.estimator().trajectory();
  results.trajectory_stamps = pipeline.estimator().keyframeStamps();
  results.support_plane = pipeline.estimator().supportPlane();
  results.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) == 0) results.peak_rss_mb = usage.ru_maxrss / 1024.0;
  if (!opt.quiet) std::fprintf(stderr, "\n");
  std::string error;
  if (!writeRunResults(opt.out, results, &error)) {
    std::cerr << "run_offline: " << error << "\n";
    return 1;
  }
  if (pipeline.background()) {
    if (!pipeline.background()->writeBinary(opt.background, &error)) {
      std::cerr << "run_offline: " << error << "\n";
      return 1;
    }
    std::printf("run_offline: background OctoMap (%zu occupied voxels of %.0f mm) in %s\n",
                pipeline.background()->occupiedCentres().size(),
                1000 * background_config.resolution_m, opt.background.c_str());
  }
  std::printf(
      "run_offline: %s on %s: %zu keyframes (%d sets, %d skipped), %zu objects, %zu contacts; "
      "%.1f s for %.1f s of recording (real-time factor %.2f); results in %s\n",
      results.method.c_str(), opt.bag.c_str(), results.keyframes.size(), results.frames_seen,
      results.frames_skipped, results.final_map.objects.size(), results.final_map.contacts.size(),
      results.wall_time_s, duration, duration > 0 ? results.wall_time_s / duration : 0.0,
      opt.out.c_str());
  int warned_keyframes = 0;
  std::string last_warning;
  for (const KeyframeResult& k : results.keyframes) {
    if (k.detection_warning.empty()) continue;
    ++warned_keyframes;
    last_warning = k.detection_warning;
  }
  if (warned_keyframes > 0) {
    std::cerr << "run_offline: warning: in " << warned_keyframes << " of "
              << results.keyframes.size() << " keyframes " << last_warning
              << " (the last one; `detections:` in " << opt.out << ")\n";
  }
  if (const int failed = failedStages(results)) {
    std::cerr << "run_offline: warning: " << failed
              << " optimisation stage(s) failed and their results were not used (`stages:` in "
              << opt.out << ")\n";
  }
  return results.keyframes.empty() ? 1 : 0;
}
