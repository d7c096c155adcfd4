// background_benchmark: the background OctoMap alone, replayed from a run. Each keyframe of a
// run_offline results file (its camera pose and its map's objects) is inserted with the depth
// image of the same stamp from the recording, with the background settings of --params; prints
// the insertion's CPU time (p50, p95, max, amortised over the keyframes) and, with --reference,
// the occupied-voxel agreement with another map (.bt). A benchmark that prints figures, not a
// test (docs/BENCHMARK.md, "Live").
//   background_benchmark --bag REC.bag --results RUN.yaml [--model-set NAME] [--models DIR]
//                        [--params FILE] [--out MAP.bt] [--reference REF.bt]
//                        [--depth-topic T] [--camera-info-topic T]
#include "command_line.h"
#include "geofusion/background/background_map.h"
#include "geofusion/common/robot_names.h"
#include "geofusion/common/statistics.h"
#include "geofusion/config/config.h"
#include "geofusion/estimation/run_results.h"
#include "geofusion/ros/conversions.h"
#include "model_set_option.h"

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <iostream>
#include <map>
#include <string>
#include <vector>

namespace geofusion {
namespace {

struct Options {
  std::string bag, results, model_set = "primitives", models, params, out, reference;
  std::string depth_topic = std::string("/") + kDepthTopic;
  std::string info_topic = std::string("/") + kCameraInfoTopic;
};

// The recording's depth images at the keyframes' stamps (nanoseconds), with their camera.
struct Frame {
  std::vector<float> depth;
  PinholeIntrinsics K;
};

bool readFrames(const Options& o, const std::vector<KeyframeResult>& keyframes,
                std::map<long long, Frame>* frames) {
  std::map<long long, bool> wanted;
  for (const KeyframeResult& k : keyframes) wanted[std::llround(k.stamp_s * 1e9)] = true;
  std::map<long long, sensor_msgs::CameraInfo> infos;
  rosbag::Bag bag;
  try {
    bag.open(o.bag, rosbag::bagmode::Read);
    for (const rosbag::MessageInstance& m :
         rosbag::View(bag, rosbag::TopicQuery({o.depth_topic, o.info_topic}))) {
      if (const auto info = m.instantiate<sensor_msgs::CameraInfo>()) {
        infos[static_cast<long long>(info->header.stamp.toNSec())] = *info;
      } else if (const auto image = m.instantiate<sensor_msgs::Image>()) {
        const long long stamp = static_cast<long long>(image->header.stamp.toNSec());
        if (!wanted.count(stamp)) continue;
        Frame& f = (*frames)[stamp];
        if (!depthToMetres(*image, &f.depth)) frames->erase(stamp);
      }
    }
  } catch (const std::exception& e) {
    std::cerr << "background_benchmark: cannot read " << o.bag << ": " << e.what() << "\n";
    return false;
  }
  CameraRectifier camera;
  for (auto it = frames->begin(); it != frames->end();) {
    const auto info = infos.find(it->first);
    if (info == infos.end()) {
      it = frames->erase(it);
      continue;
    }
    // The estimator's depth: made pinhole for a camera with a lens distortion.
    std::string error;
    if (!camera.update(info->second, &error) || !camera.rectifyDepth(&it->second.depth)) {
      std::cerr << "background_benchmark: frame skipped: "
                << (error.empty() ? "depth not the size camera_info says" : error) << "\n";
      it = frames->erase(it);
      continue;
    }
    it->second.K = camera.K();
    ++it;
  }
  return true;
}

int run(const Options& o) {
  GeoFusionConfig config;
  ConfigReport report;
  if (!o.params.empty() && !loadConfigFile(o.params, &config, &report)) {
    for (const auto& e : report.errors) std::cerr << "background_benchmark: " << e << "\n";
    return 1;
  }
  ModelSet models;
  if (!loadModelSetOption("background_benchmark", o.model_set, o.models, &models)) return 1;
  RunResults results;
  std::string error;
  if (!readRunResults(o.results, models, &results, &error)) {
    std::cerr << "background_benchmark: " << error << "\n";
    return 1;
  }
  std::map<long long, Frame> frames;
  if (!readFrames(o, results.keyframes, &frames)) return 1;
  BackgroundMap map(config.background);
  map.prepare(models);
  std::vector<double> ms;
  std::size_t points = 0, missing = 0, passed_over = 0;
  for (const KeyframeResult& k : results.keyframes) {
    const auto f = frames.find(std::llround(k.stamp_s * 1e9));
    if (f == frames.end()) {
      ++missing;
      continue;
    }
    const double start = threadCpuMs();
    if (!map.wanted(k.T_map_cam)) {
      ms.push_back(threadCpuMs() - start);
      ++passed_over;
      continue;
    }
    std::vector<MaskObject> objects;
    for (const ObjectEstimate& obj : k.objects) objects.push_back({obj.model, obj.T_map_obj});
    points += static_cast<std::size_t>(
        map.insert(DepthImageView{f->second.depth.data(), f->second.K.width, f->second.K.height},
                   f->second.K, k.T_map_cam, objects));
    ms.push_back(threadCpuMs() - start);
  }
  if (ms.empty()) {
    std::cerr << "background_benchmark: no keyframe of " << o.results << " has its depth in "
              << o.bag << "\n";
    return 1;
  }
  double total = 0;
  for (double t : ms) total += t;
  std::printf(
      "background_benchmark: %zu keyframes (%zu without depth, %zu passed over: camera still), "
      "%.0f points an insertion, CPU ms a keyframe p50 %.1f p95 %.1f max %.1f mean (amortised) "
      "%.1f; %zu occupied voxels\n",
      ms.size(), missing, passed_over,
      double(points) / std::max<std::size_t>(1, ms.size() - passed_over), percentile(ms, 0.5),
      percentile(ms, 0.95), *std::max_element(ms.begin(), ms.end()), total / ms.size(),
      map.occupiedVoxels().size());
  if (!o.out.empty() && !map.writeBinary(o.out, &error)) {
    std::cerr << "background_benchmark: " << error << "\n";
    return 1;
  }
  if (!o.reference.empty()) {
    BackgroundMap reference(config.background);
    if (!reference.readBinary(o.reference, &error)) {
      std::cerr << "background_benchmark: " << error << "\n";
      return 1;
    }
    const OccupiedAgreement a = compareOccupied(reference, map);
    std::printf(
        "background_benchmark: against %s: %zu and %zu occupied voxels, %zu in both: IoU %.3f, "
        "%.3f of the reference kept, %.3f of this map in the reference\n",
        o.reference.c_str(), a.a, a.b, a.both, a.iou(), a.ofA(), a.ofB());
  }
  return 0;
}

}  // namespace
}  // namespace geofusion

int main(int argc, char** argv) {
  geofusion::Options o;
  geofusion::CommandLine args;
  args.value("--bag", &o.bag);
  args.value("--results", &o.results);
  args.value("--model-set", &o.model_set);
  args.value("--models", &o.models);
  args.value("--params", &o.params);
  args.value("--out", &o.out);
  args.value("--reference", &o.reference);
  args.value("--depth-topic", &o.depth_topic);
  args.value("--camera-info-topic", &o.info_topic);
  try {
    args.parse(argc, argv, [] {
      std::cerr << "usage: background_benchmark --bag REC.bag --results RUN.yaml [--model-set "
                   "NAME] [--models DIR] [--params FILE] [--out MAP.bt] [--reference REF.bt]\n";
    });
  } catch (const std::exception& e) {
    std::cerr << "background_benchmark: " << e.what() << "\n";
    return 2;
  }
  if (o.bag.empty() || o.results.empty()) {
    std::cerr << "background_benchmark: --bag and --results are needed\n";
    return 2;
  }
  return geofusion::run(o);
}
