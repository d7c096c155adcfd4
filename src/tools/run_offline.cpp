// run_offline: runs the scene estimator over a recording as fast as the machine allows (rosbag
// C++ API, no ROS master) and writes a results file (docs/results.md).
//
//   run_offline --bag FILE.bag --out results.yaml [--params FILE.yaml] [--set KEY=VALUE]...
//       [--method geofusion|fbf|fbfr|bslam|rfront] [--model-set primitives|ycb_video|FILE.yaml]
//       [--models DIR] [--keyframe-every N]
//       [--rgb-topic T] [--depth-topic T] [--camera-info-topic T] [--detections-topic T]
//       [--odom-frame odom]
//       [--background FILE.bt] [--initial-map PREFIX] [--save-map PREFIX]
//       [--bop-results FILE.csv [--bop-scene-id N]] [--quiet]
//   run_offline [--params FILE.yaml] [--set KEY=VALUE]... --print-params
// Frames are made and judged as the estimator node makes and judges them (the same synchroniser,
// EstimatorPipeline's admission, checks and cap). Nothing is written unless the run succeeds:
// the output paths are checked before the run, and a run without a keyframe says why (the bag's
// topics and types, what is missing, how far apart the stamps were) and exits 1.
// The configuration is the nodes' (config/config.h): the file of --params, then --set and the
// shorthands (--method = method, --model-set = model_set.name, --models = model_set.dir,
// --keyframe-every = keyframes.every_n_frames) in the order given; it is written into the
// results. --bop-results also writes the run as BOP results (bop_results.h: every keyframe's map
// objects in view, in BOP's model frame; scene id --bop-scene-id, image id the keyframe index,
// object id the class id).
#include "command_line.h"
#include "config_option.h"
#include "geofusion/common/ingestion.h"
#include "geofusion/common/robot_names.h"
#include "geofusion/config/config.h"
#include "geofusion/estimation/bop_results.h"
#include "geofusion/estimation/map_stability.h"
#include "geofusion/estimation/run_results.h"
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/ros/estimator_pipeline.h"
#include "geofusion/ros/rgbd_subscriber.h"
#include "geofusion/ros/vision_detections.h"
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
#include <boost/bind/bind.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string>

namespace {

struct Options {
  std::string bag, out;
  geofusion::ConfigOptions config;  ///< --params, --set and the shorthands
  bool print_params = false;
  std::string rgb_topic = std::string("/") + geofusion::kRgbTopic;
  std::string depth_topic = std::string("/") + geofusion::kDepthTopic;
  std::string info_topic = std::string("/") + geofusion::kCameraInfoTopic;
  std::string detections_topic = std::string("/") + geofusion::kDetectionsTopic;
  std::string odom_frame = geofusion::kOdomFrame;
  std::string background;   ///< .bt file of the background OctoMap; empty: none
  std::string save_map;     ///< prefix to save the final map under (map_store.h); empty: none
  std::string initial_map;  ///< a saved map to continue; empty: none
  std::string bop_results;  ///< BOP results CSV to write; empty: none
  int bop_scene_id = 0;
  bool quiet = false;
};

void usage() {
  std::cerr
      << "usage: run_offline --bag FILE.bag --out RESULTS.yaml [--params FILE.yaml]\n"
         "         [--set KEY=VALUE]... [--method geofusion|fbf|fbfr|bslam|rfront]\n"
         "         [--model-set primitives|ycb_video|FILE.yaml] [--models DIR]\n"
         "         [--keyframe-every N] [--rgb-topic T] [--depth-topic T] [--camera-info-topic T]\n"
         "         [--detections-topic T] [--odom-frame odom] [--background FILE.bt]\n"
         "         [--initial-map PREFIX] [--save-map PREFIX]\n"
         "         [--bop-results FILE.csv [--bop-scene-id N]] [--quiet]\n"
         "       run_offline [--params FILE.yaml] [--set KEY=VALUE]... --print-params\n";
}

Options parse(int argc, char** argv) {
  Options o;
  geofusion::CommandLine args;
  args.value("--bag", &o.bag);
  args.value("--out", &o.out);
  o.config.declare(&args);
  o.config.shorthand(&args, "--method", "method");
  o.config.shorthand(&args, "--model-set", "model_set.name");
  o.config.shorthand(&args, "--models", "model_set.dir");
  o.config.shorthand(&args, "--keyframe-every", "keyframes.every_n_frames");
  args.toggle("--print-params", &o.print_params);
  args.value("--rgb-topic", &o.rgb_topic);
  args.value("--depth-topic", &o.depth_topic);
  args.value("--camera-info-topic", &o.info_topic);
  args.value("--detections-topic", &o.detections_topic);
  args.value("--odom-frame", &o.odom_frame);
  args.value("--background", &o.background);
  args.value("--save-map", &o.save_map);
  args.value("--initial-map", &o.initial_map);
  args.value("--bop-results", &o.bop_results);
  args.value("--bop-scene-id", &o.bop_scene_id);
  args.toggle("--quiet", &o.quiet);
  args.parse(argc, argv, usage);
  if (!o.print_params && (o.bag.empty() || o.out.empty()))
    throw std::runtime_error("--bag and --out are required");
  return o;
}

// Whether `path` can be written: a probe file beside it is made and removed (before hours of
// work, not after).
bool checkWritable(const std::string& path, std::string* error) {
  const std::string probe = path + ".probe";
  std::FILE* f = std::fopen(probe.c_str(), "w");
  if (!f) {
    *error = "cannot write " + path + ": " + std::strerror(errno);
    return false;
  }
  std::fclose(f);
  std::remove(probe.c_str());
  return true;
}

// A vision_msgs/Detection3DArray of the bag as the package's DetectionArray (null, with the
// reason, when it is of another layout or does not decode).
geofusion::DetectionArrayConstPtr fromVisionMsgs(const rosbag::MessageInstance& m,
                                                 geofusion::VisionDetectionConverter* converter,
                                                 std::string* error) {
  std::vector<std::uint8_t> bytes(m.size());
  ros::serialization::OStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  m.write(stream);
  auto out = boost::make_shared<geofusion::DetectionArray>();
  if (!converter->convert(m.getDataType(), m.getMD5Sum(), bytes.data(), bytes.size(), out.get(),
                          error))
    return nullptr;
  return out;
}

// What a reader of a broken bag should do next.
std::string bagHint(const std::string& bag) {
  return " (a truncated or unindexed bag, e.g. a recording killed before it closed? `rosbag "
         "reindex " +
         bag + "` rebuilds its index, keeping the original as .orig.bag)";
}

/// Stamps of each input as read, to say how far apart they were when nothing synchronised.
struct StampLog {
  std::vector<std::vector<double>> stamps;  ///< per input, in the order of Options' topics
  explicit StampLog(std::size_t inputs) : stamps(inputs) {}
  /// The smallest |t_a - t_b| between a stamp of input a and one of input b.
  double closest(std::size_t a, std::size_t b) const {
    std::vector<double> other = stamps[b];
    std::sort(other.begin(), other.end());
    double best = std::numeric_limits<double>::infinity();
    for (double t : stamps[a]) {
      const auto it = std::lower_bound(other.begin(), other.end(), t);
      if (it != other.end()) best = std::min(best, *it - t);
      if (it != other.begin()) best = std::min(best, t - *std::prev(it));
    }
    return best;
  }
};

// Why a run made no keyframe: the bag's topics and types, what is missing, the stamp offsets
// between the inputs, and the frames dropped by reason.
std::string noKeyframeReport(const Options& o, const rosbag::Bag& bag, const StampLog& log,
                             const geofusion::EstimatorPipeline& pipeline,
                             const geofusion::GeoFusionConfig& config) {
  std::ostringstream s;
  s << "no keyframe was made from " << o.bag << ".\n  The bag has:";
  std::map<std::string, std::string> types;
  rosbag::View all(bag);
  for (const rosbag::ConnectionInfo* c : all.getConnections()) types[c->topic] = c->datatype;
  for (const auto& [topic, type] : types) s << "\n    " << topic << " (" << type << ")";
  const std::vector<std::pair<std::string, std::string>> wanted = {
      {o.rgb_topic, "sensor_msgs/Image"},
      {o.depth_topic, "sensor_msgs/Image"},
      {o.info_topic, "sensor_msgs/CameraInfo"},
      {o.detections_topic, "geofusion/DetectionArray"}};
  const auto accepted = [](const std::string& wanted, const std::string& type) {
    return type == wanted ||
           (wanted == "geofusion/DetectionArray" && type == geofusion::kVisionDetectionsType);
  };
  bool missing = false;
  for (const auto& [topic, type] : wanted) {
    const auto it = types.find(topic);
    if (it == types.end()) {
      s << "\n  Missing: " << topic << " (" << type << "); set it with the --*-topic options";
      missing = true;
    } else if (!accepted(type, it->second)) {
      s << "\n  Wrong type: " << topic << " is " << it->second << ", expected " << type
        << (type == "geofusion/DetectionArray"
                ? std::string(" or ") + geofusion::kVisionDetectionsType
                : "");
      missing = true;
    }
  }
  if (!missing) {
    const double spread = config.input.sync_max_interval_s;
    for (std::size_t i = 0; i + 1 < wanted.size(); ++i) {
      const double d = log.closest(3, i);
      s << "\n  Closest stamps of " << wanted[3].first << " and " << wanted[i].first << ": ";
      if (std::isfinite(d))
        s << std::fixed << std::setprecision(3) << d << " s apart"
          << (d > spread ? " (more than input.sync_max_interval_s)" : "");
      else
        s << "none to compare";
    }
    s << "\n  Synchronised frames: " << pipeline.framesSeen() << ", " << pipeline.drops().summary();
    if (pipeline.drops().of(geofusion::FrameDrop::kNoOdometry) > 0)
      s << "\n  No camera pose: " << pipeline.lastPoseError() << " (--odom-frame is "
        << o.odom_frame << ")";
  }
  return s.str();
}

// The output paths, checked before the run: false, having said why, when one cannot be written.
bool checkOutputs(const Options& opt, std::string* error) {
  for (const std::string& out :
       {opt.out, opt.background, opt.save_map.empty() ? "" : opt.save_map + ".yaml",
        opt.bop_results}) {
    if (!out.empty() && !checkWritable(out, error)) {
      std::cerr << "run_offline: " << *error << "; nothing was run\n";
      return false;
    }
  }
  return true;
}

bool openBag(const std::string& path, rosbag::Bag* bag) {
  try {
    bag->open(path, rosbag::bagmode::Read);
  } catch (const std::exception& e) {
    std::cerr << "run_offline: cannot read " << path << ": " << e.what() << bagHint(path) << "\n";
    return false;
  }
  return true;
}

// --initial-map: the saved map the run continues (none given: nothing to do).
bool resumeInitialMap(const Options& opt, const geofusion::ModelSet& models,
                      geofusion::EstimatorPipeline* pipeline, std::string* error) {
  if (opt.initial_map.empty()) return true;
  geofusion::RunResults resumed;
  if (!pipeline->loadMap(opt.initial_map, models, &resumed, error)) {
    std::cerr << "run_offline: --initial-map: " << *error << "; nothing was run\n";
    return false;
  }
  std::cerr << "run_offline: continuing the map " << opt.initial_map << " ("
            << resumed.final_map.objects.size() << " objects)\n";
  return true;
}

/// What reading the recording keeps: the recording's TF, and each input's messages as read.
struct BagReading {
  explicit BagReading(const Options& o)
      : topics{o.rgb_topic, o.depth_topic, o.info_topic, o.detections_topic},
        stamps(topics.size()),
        counts(topics.size(), 0) {}
  std::vector<std::string> topics;  ///< rgb, depth, camera_info, detections
  StampLog stamps;
  std::vector<std::size_t> counts;  ///< messages read of each input
  double newest_stamp_s = 0.0;
  std::unique_ptr<tf2::BufferCore> tf;
  int warned = 0;  ///< warnings printed (at most 5, of all kinds together)
};

// The whole recording's TF (an offline run may look anywhere in time), its odom -> base samples
// into the pipeline's timeline.
void readTransforms(const Options& opt, const rosbag::Bag& bag,
                    geofusion::EstimatorPipeline* pipeline, BagReading* reading,
                    geofusion::RunResults* results) {
  using namespace geofusion;
  rosbag::View all(bag);
  results->recording_duration_s = (all.getEndTime() - all.getBeginTime()).toSec();
  reading->tf = std::make_unique<tf2::BufferCore>(
      ros::Duration(std::max(10.0, results->recording_duration_s + 10.0)));
  pipeline->odometry() = OdometryTimeline(std::numeric_limits<double>::infinity());
  for (const rosbag::MessageInstance& m :
       rosbag::View(bag, rosbag::TopicQuery(std::vector<std::string>{"/tf", "/tf_static"}))) {
    const auto msg = m.instantiate<tf2_msgs::TFMessage>();
    if (!msg) continue;
    const bool is_static = m.getTopic() == "/tf_static";
    for (const auto& t : msg->transforms) {
      try {
        reading->tf->setTransform(t, "bag", is_static);
      } catch (const std::exception& e) {
        if (reading->warned++ < 5)
          std::cerr << "run_offline: transform ignored: " << e.what() << "\n";
        continue;
      }
      if (!is_static && t.header.frame_id == opt.odom_frame)
        pipeline->odometry().add(t.header.stamp.toSec());
    }
  }
}

// One synchronised frame into the pipeline, its camera pose from the recording's TF; a keyframe
// into the results.
void processFrame(const Options& opt, const sensor_msgs::Image& depth,
                  const sensor_msgs::CameraInfo& info, const geofusion::DetectionArray& dets,
                  geofusion::EstimatorPipeline* pipeline, BagReading* reading,
                  geofusion::RunResults* results) {
  using namespace geofusion;
  EstimatorPipeline::CameraPose pose;
  try {
    pose.T_odom_cam = tf2::transformToEigen(
        reading->tf->lookupTransform(opt.odom_frame, dets.header.frame_id, dets.header.stamp));
    pose.found = true;
  } catch (const std::exception& e) {
    pose.error = e.what();
  }
  KeyframeResult r;
  const auto outcome = pipeline->process(depth, info, dets, pose, reading->newest_stamp_s, &r);
  if (outcome == EstimatorPipeline::Outcome::kDropped) {
    if (reading->warned++ < 5)
      std::cerr << "run_offline: frame at " << dets.header.stamp
                << " dropped: " << toString(pipeline->lastDrop())
                << (pipeline->lastDrop() == FrameDrop::kNoOdometry ? ": " + pose.error
                    : pipeline->lastDrop() == FrameDrop::kBadCameraInfo
                        ? ": " + pipeline->lastCameraError()
                        : "")
                << "\n";
    return;
  }
  if (outcome != EstimatorPipeline::Outcome::kKeyframe) return;
  results->keyframes.push_back(r);
}

// The recording's frames into the synchroniser, whose callback makes the keyframes (into
// `results`); a progress bar unless --quiet.
void readFrames(const Options& opt, const rosbag::Bag& bag,
                geofusion::RgbdSubscriber::DetectionSync* sync,
                geofusion::VisionDetectionConverter* vision, const geofusion::RunResults& results,
                BagReading* reading, std::string* error) {
  using namespace geofusion;
  const std::vector<std::string>& topics = reading->topics;
  rosbag::View view(bag, rosbag::TopicQuery(topics));
  const std::size_t total = view.size();
  std::size_t read = 0;
  for (const rosbag::MessageInstance& m : view) {
    ++read;
    const std::size_t input = static_cast<std::size_t>(
        std::find(topics.begin(), topics.end(), m.getTopic()) - topics.begin());
    ros::Time stamp;
    const std::size_t before = results.keyframes.size();
    auto note = [&](const auto& msg) {
      stamp = msg->header.stamp;
      ++reading->counts[input];
      reading->stamps.stamps[input].push_back(stamp.toSec());
      reading->newest_stamp_s = std::max(reading->newest_stamp_s, stamp.toSec());
    };
    if (input == 0 || input == 1) {
      auto msg = m.instantiate<sensor_msgs::Image>();
      if (!msg) continue;
      note(msg);
      if (input == 0)
        sync->add<0>(ros::MessageEvent<sensor_msgs::Image const>(msg, m.getTime()));
      else
        sync->add<1>(ros::MessageEvent<sensor_msgs::Image const>(msg, m.getTime()));
    } else if (input == 2) {
      auto msg = m.instantiate<sensor_msgs::CameraInfo>();
      if (!msg) continue;
      note(msg);
      sync->add<2>(ros::MessageEvent<sensor_msgs::CameraInfo const>(msg, m.getTime()));
    } else {
      auto msg = m.getDataType() == kVisionDetectionsType
                     ? fromVisionMsgs(m, vision, error)
                     : m.instantiate<geofusion::DetectionArray>();
      if (!msg) {
        if (!error->empty() && reading->warned++ < 5)
          std::cerr << "run_offline: detections at " << m.getTime() << " dropped: " << *error
                    << "\n";
        error->clear();
        continue;
      }
      note(msg);
      sync->add<3>(ros::MessageEvent<geofusion::DetectionArray const>(msg, m.getTime()));
    }
    if (!opt.quiet && results.keyframes.size() > before && results.keyframes.size() % 10 == 0) {
      const int percent = static_cast<int>(100.0 * read / std::max<std::size_t>(1, total));
      std::fprintf(stderr, "\r[%-40s] %3d%%  %zu keyframes, %zu objects",
                   std::string(percent * 40 / 100, '#').c_str(), percent, results.keyframes.size(),
                   results.keyframes.back().objects.size());
    }
  }
}

// Reads the recording into the pipeline: its whole TF first, then the frames through the node's
// synchroniser. False, having said why, when the bag cannot be read.
bool readBag(const Options& opt, const geofusion::GeoFusionConfig& config, const rosbag::Bag& bag,
             geofusion::EstimatorPipeline* pipeline, geofusion::VisionDetectionConverter* vision,
             geofusion::RunResults* results, BagReading* reading, std::string* error) {
  using namespace geofusion;
  RgbdSubscriber::Config sync_config;
  sync_config.queue_size = config.input.queue_size;
  sync_config.max_interval_s = config.input.sync_max_interval_s;
  auto sync = RgbdSubscriber::makeDetectionSync(sync_config);
  try {
    readTransforms(opt, bag, pipeline, reading, results);
    const boost::function<void(const sensor_msgs::ImageConstPtr&, const sensor_msgs::ImageConstPtr&,
                               const sensor_msgs::CameraInfoConstPtr&,
                               const geofusion::DetectionArrayConstPtr&)>
        on_frame = [&](const sensor_msgs::ImageConstPtr&, const sensor_msgs::ImageConstPtr& depth,
                       const sensor_msgs::CameraInfoConstPtr& info,
                       const geofusion::DetectionArrayConstPtr& dets) {
          processFrame(opt, *depth, *info, *dets, pipeline, reading, results);
        };
    using boost::placeholders::_1, boost::placeholders::_2, boost::placeholders::_3,
        boost::placeholders::_4;
    sync->registerCallback(boost::bind(on_frame, _1, _2, _3, _4));
    readFrames(opt, bag, sync.get(), vision, *results, reading, error);
  } catch (const std::exception& e) {  // rosbag's and deserialisation's
    std::cerr << "\nrun_offline: cannot read " << opt.bag << ": " << e.what() << bagHint(opt.bag)
              << "; nothing written\n";
    return false;
  }
  return true;
}

// The final solve and the pipeline's counts, with what only this run knows (its record, its wall
// time since `start` and its peak memory).
void finishResults(geofusion::EstimatorPipeline* pipeline,
                   std::chrono::steady_clock::time_point start, geofusion::RunResults* results) {
  geofusion::RunResults finished = pipeline->currentMap();
  finished.method = std::move(results->method);
  finished.config_yaml = std::move(results->config_yaml);
  finished.source = std::move(results->source);
  finished.model_set = std::move(results->model_set);
  finished.recording_duration_s = results->recording_duration_s;
  finished.keyframes = std::move(results->keyframes);
  *results = std::move(finished);
  results->wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) == 0) results->peak_rss_mb = usage.ru_maxrss / 1024.0;
}

// The background, the results and the map of --save-map; `occupied`: the background's occupied
// voxels. False, having said why, when one cannot be written.
bool writeOutputs(const Options& opt, geofusion::EstimatorPipeline* pipeline,
                  geofusion::RunResults* results, std::size_t* occupied, std::string* error) {
  using namespace geofusion;
  // The background first: when the results (the run's record) cannot be written, it goes too.
  if (BackgroundWorker* background = pipeline->background()) {
    bool written = false;
    background->withMap([&](BackgroundMap& map) {
      written = map.writeBinary(opt.background, error);
      *occupied = map.occupiedCentres().size();
    });
    if (!written) {
      std::cerr << "run_offline: " << *error << "; nothing written\n";
      return false;
    }
    results->has_background = true;
    results->background = background->stats();
  }
  if (!writeRunResults(opt.out, *results, error)) {
    if (pipeline->background()) std::remove(opt.background.c_str());
    std::cerr << "run_offline: " << *error << "; nothing written\n";
    return false;
  }
  if (!opt.bop_results.empty()) {
    BopIds ids;
    ids.scene_id = opt.bop_scene_id;
    if (!writeBopResults(opt.bop_results, keyframeMapImages(*results), pipeline->intrinsics(), ids,
                         error)) {
      std::cerr << "run_offline: --bop-results: " << *error << "\n";
      return false;
    }
  }
  if (!opt.save_map.empty()) {
    RunResults map = *results;
    map.keyframes.clear();  // the map, not the run's record
    MapFiles files;
    if (!pipeline->saveMap(opt.save_map, std::move(map), &files, error)) {
      std::cerr << "run_offline: --save-map: " << *error << "\n";
      return false;
    }
    std::printf("run_offline: map saved to %s%s%s\n", files.yaml.c_str(),
                files.background.empty() ? "" : " and ", files.background.c_str());
  }
  return true;
}

// The final map under gravity on its support plane (physics/stability.h), and its support graph
// as a plan with the check's verdicts (scene_graph.h; written with the results).
geofusion::physics::StabilityResult checkFinalMap(const geofusion::GeoFusionConfig& config,
                                                  geofusion::RunResults* results,
                                                  double* check_ms) {
  using namespace geofusion;
  const auto start = std::chrono::steady_clock::now();
  physics::StabilityResult s =
      checkMapStability(results->final_map.objects, &results->support_plane,
                        config.estimator.gravity, config.estimator.physics);
  results->scene_graph = mapSupportGraph(results->final_map.objects, results->final_map.contacts,
                                         config.estimator.gravity, &s, config.scene_graph);
  results->has_scene_graph = true;
  *check_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return s;
}

// Would the final map stand? And what can be taken first?
void printStability(const geofusion::GeoFusionConfig& config, const geofusion::RunResults& results,
                    const geofusion::physics::StabilityResult& s, double check_ms) {
  using namespace geofusion;
  auto name = [&](int id) {
    return supportGraphName(results.scene_graph,
                            id == physics::kPlaneId ? SupportGraph::kSupportPlaneId : id);
  };
  std::printf(
      "run_offline: stability (%.1f s of gravity, checked in %.0f ms): %d of %d objects stable, "
      "%d more start interpenetrating; motion %.1f mm mean, %.1f mm / %.1f deg max",
      config.estimator.physics.duration_s, check_ms, s.stable, s.checked, s.interpenetrating,
      1000 * s.mean_translation_m, 1000 * s.max_translation_m, s.max_rotation_deg);
  if (s.least_stable_pair.first != -1) {
    std::printf("; least stable pair %s / %s (%.1f mm)", name(s.least_stable_pair.first).c_str(),
                name(s.least_stable_pair.second).c_str(), 1000 * s.least_stable_pair_m);
  }
  std::printf("\n");
  for (const std::string& w : s.warnings) std::printf("run_offline: stability: %s\n", w.c_str());
  const SupportGraph& g = results.scene_graph;
  std::string order;
  for (std::size_t i = 0; i < g.removal_order.size(); ++i)
    order += (i ? ", " : "") + name(g.removal_order[i]);
  const auto free = std::count_if(g.nodes.begin(), g.nodes.end(),
                                  [](const SupportGraphNode& n) { return n.free_to_pick; });
  std::printf("run_offline: scene graph: %ld of %zu objects free to pick; removal order: %s\n",
              static_cast<long>(free), g.nodes.size(), order.empty() ? "none" : order.c_str());
  for (const std::string& w : g.warnings) std::printf("run_offline: scene graph: %s\n", w.c_str());
}

// What the run made: the background, keyframes and objects, its speed, the detections used.
void printSummary(const Options& opt, const geofusion::GeoFusionConfig& config,
                  const geofusion::VisionDetectionConverter& vision,
                  const geofusion::RunResults& results, std::size_t occupied,
                  const geofusion::physics::StabilityResult& stability, double check_ms,
                  geofusion::EstimatorPipeline* pipeline) {
  using namespace geofusion;
  if (pipeline->background()) {
    const BackgroundStats& b = results.background;
    std::printf(
        "run_offline: background OctoMap (%zu occupied voxels of %.0f mm) in %s; %zu keyframes "
        "inserted, %zu passed over (camera still), %.1f ms a keyframe amortised (insertions p50 "
        "%.1f, p95 %.1f, max %.1f ms CPU)\n",
        occupied, 1000 * config.background.resolution_m, opt.background.c_str(), b.inserted,
        b.still, b.amortisedMs(), b.p50_ms, b.p95_ms, b.max_ms);
  }
  const double duration = results.recording_duration_s;
  std::printf(
      "run_offline: %s on %s: %zu keyframes (%d synchronised frames, %s), %zu objects, %zu "
      "contacts; %.1f s for %.1f s of recording (real-time factor %.2f); results in %s\n",
      results.method.c_str(), opt.bag.c_str(), results.keyframes.size(), results.frames_seen,
      pipeline->drops().summary().c_str(), results.final_map.objects.size(),
      results.final_map.contacts.size(), results.wall_time_s, duration,
      duration > 0 ? results.wall_time_s / duration : 0.0, opt.out.c_str());
  std::printf("run_offline: detections: %s\n", pipeline->tally().summary().c_str());
  printStability(config, results, stability, check_ms);
  std::printf("run_offline: objects removed: %s; relocalisation searched: %s\n",
              reasonsLine(removalsByReason(results)).c_str(),
              reasonsLine(relocalisationsByDecision(results)).c_str());
  if (vision.counts().messages + vision.counts().rejected > 0) {
    std::printf(
        "run_offline: vision_msgs detections: %zu messages, %zu detections converted%s%s\n",
        vision.counts().messages, vision.counts().detections,
        vision.droppedSummary().empty() ? "" : "; dropped: ", vision.droppedSummary().c_str());
  }
}

// What the run's figures should not hide: keyframes over budget, detections beyond the cap,
// detection warnings and failed optimisation stages.
void printWarnings(const Options& opt, const geofusion::GeoFusionConfig& config,
                   const geofusion::EstimatorPipeline& pipeline,
                   const geofusion::RunResults& results) {
  using namespace geofusion;
  if (results.keyframes_over_budget > 0) {
    std::cerr << "run_offline: warning: " << results.keyframes_over_budget << " of "
              << results.keyframes.size()
              << " keyframes took longer than input.keyframe_budget_ms ("
              << config.ingestion.keyframe_budget_ms << " ms)\n";
  }
  if (const std::size_t capped =
          pipeline.tally().skipped[static_cast<std::size_t>(SkipReason::kOverCap)]) {
    std::cerr << "run_offline: warning: " << capped
              << " detections beyond input.max_detections_per_frame ("
              << config.checks.max_detections << ") dropped, the lowest scores first\n";
  }
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
}

}  // namespace

int main(int argc, char** argv) {
  using namespace geofusion;
  Options opt;
  if (!geofusion::readCommandLine("run_offline", usage, [&] { opt = parse(argc, argv); })) return 2;
  GeoFusionConfig config;
  if (!opt.config.apply("run_offline", &config)) return 2;
  if (opt.print_params) {
    std::cout << configYaml(config);
    return 0;
  }
  std::string error;
  if (!checkOutputs(opt, &error)) return 1;
  if (!opt.quiet)
    std::cerr << "run_offline: configuration (differences from the defaults):\n"
              << configDiff(config) << "\n";
  const Method method = config.estimator.method;
  ModelSet models;
  if (!loadModelSetOption("run_offline", config.model_set.name, config.model_set.dir, &models,
                          config.model_set.surface_features))
    return 1;

  ros::Time::init();  // the synchroniser stamps its events; no master needed
  rosbag::Bag bag;
  if (!openBag(opt.bag, &bag)) return 1;
  const auto start = std::chrono::steady_clock::now();
  const BackgroundMapConfig& background_config = config.background;
  EstimatorPipeline pipeline(models, config.estimator, config.keyframes, config.checks,
                             opt.background.empty() ? nullptr : &background_config,
                             config.ingestion);
  // Every keyframe into the background, in order, whether it runs in a thread or not: a run
  // repeats; its CPU time is measured all the same.
  if (pipeline.background()) pipeline.background()->setWait(true);
  if (!resumeInitialMap(opt, models, &pipeline, &error)) return 1;
  std::map<std::int64_t, ModelClass> class_map;
  if (!makeVisionClassMap(config.vision_msgs.class_map, models, &class_map, &error)) {
    std::cerr << "run_offline: " << error << "; nothing was run\n";
    return 1;
  }
  VisionDetectionConverter vision(std::move(class_map));
  RunResults results;
  results.method = toString(method);
  results.config_yaml = configYaml(config);
  results.source = opt.bag;
  results.model_set = models.name();

  BagReading reading(opt);
  if (!readBag(opt, config, bag, &pipeline, &vision, &results, &reading, &error)) return 1;
  if (!opt.quiet) std::fprintf(stderr, "\n");
  pipeline.setUnsynchronised(unsynchronisedFrames(reading.counts, pipeline.framesSeen()));
  if (results.keyframes.empty()) {
    std::cerr << "run_offline: " << noKeyframeReport(opt, bag, reading.stamps, pipeline, config)
              << "\nrun_offline: nothing written\n";
    return 1;
  }
  finishResults(&pipeline, start, &results);
  double check_ms = 0.0;
  const physics::StabilityResult stability = checkFinalMap(config, &results, &check_ms);
  std::size_t occupied = 0;
  if (!writeOutputs(opt, &pipeline, &results, &occupied, &error)) return 1;
  printSummary(opt, config, vision, results, occupied, stability, check_ms, &pipeline);
  printWarnings(opt, config, pipeline, results);
  return 0;
}
