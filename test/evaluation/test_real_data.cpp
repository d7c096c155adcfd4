// Real camera frames (../shared/data/real, README there; never copied into the repository):
// - YCB-Video (Asus Xtion) frames with detections made from their 6D ground truth, biased 2-4 cm
//   along the viewing ray as colour-only estimators err: depth refinement brings them to the
//   surface, the estimator maps every object and nothing else;
// - 7-Scenes (Kinect v1) frames: the visual odometry tracks all 300 without losing one.
// Skipped with a message when the data or the YCB-Video models are absent.
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/evaluation/metrics.h"
#include "geofusion/evaluation/real_datasets.h"
#include "geofusion/evaluation/trajectory_metrics.h"
#include "geofusion/odometry/visual_odometry.h"
#include "geofusion/render/renderer.h"
#include "geofusion/simulation/depth_sensor.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

namespace geofusion {
namespace {

std::string realDir() {
  if (const char* env = std::getenv("GEOFUSION_REAL_DIR")) return env;
  return std::string(GEOFUSION_SOURCE_DIR) + "/../shared/data/real";
}

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct VideoRun {
  std::vector<double> ray_error_before_m, ray_error_after_m;  ///< |along the ray|, per detection
  int detections = 0, refined = 0;
  int objects = 0;        ///< ground-truth objects with a detection
  int mapped = 0;         ///< ... in the final map with their class within 2 cm
  int false_objects = 0;  ///< final map objects with no ground-truth object of their class near
  std::vector<std::string> report;
};

/// The frames of one YCB-Video folder through GeoFusion, the camera at its true poses (hand-held:
/// the dataset's trajectory is the only odometry there is).
VideoRun runVideo(const std::string& dir, const ModelSet& models) {
  VideoRun run;
  RealSequence seq;
  std::string error;
  EXPECT_TRUE(readRealSequence(dir, "auto", 30.0, &seq, &error)) << error;
  if (seq.frames.empty()) return run;
  EXPECT_EQ(seq.format, "ycbv");
  const std::vector<std::string> names = classNamesById(models);
  TruthDetectorModel detector;
  detector.ray_bias_min_m = 0.02;
  detector.ray_bias_max_m = 0.04;
  detector.seed = 31;
  TruthDetector detect(detector);
  EstimatorConfig config;  // GeoFusion, depth refinement on
  SceneEstimator estimator(models, config);
  std::vector<int> seen_ids;
  for (RealFrame& f : seq.frames) {
    EXPECT_TRUE(f.has_camera_pose) << f.name;
    EXPECT_TRUE(loadLabelVisibility(&f, &error)) << error;
    std::vector<float> depth;
    int width = 0, height = 0;
    if (!loadDepthMetres(f, &depth, &width, &height, &error)) {
      ADD_FAILURE() << error;
      return run;
    }
    Keyframe kf;
    kf.stamp_s = f.stamp_s;
    kf.T_odom_cam = f.T_world_cam;
    kf.K = f.K;
    kf.depth = DepthImageView{depth.data(), width, height};
    kf.detections = detect.detect(f, names, 400);
    const KeyframeResult r = estimator.addKeyframe(kf);
    for (std::size_t k = 0; k < kf.detections.size() && k < r.detections.size(); ++k) {
      const int id = kf.detections[k].class_id;
      const auto truth = std::find_if(f.objects.begin(), f.objects.end(),
                                      [&](const RealObjectTruth& o) { return o.obj_id == id; });
      if (truth == f.objects.end()) continue;
      if (std::find(seen_ids.begin(), seen_ids.end(), id) == seen_ids.end()) seen_ids.push_back(id);
      ++run.detections;
      if (r.detections[k].refinement == RefinementOutcome::kAccepted) ++run.refined;
      run.ray_error_before_m.push_back(
          std::abs(alongRayError(r.detections[k].T_cam_in, truth->T_cam_obj)));
      run.ray_error_after_m.push_back(
          std::abs(alongRayError(r.detections[k].T_cam_out, truth->T_cam_obj)));
    }
  }
  const KeyframeResult final_map = estimator.finish();
  // The true objects in the world frame (static scene: from the first frame that has them).
  std::vector<std::pair<std::string, Eigen::Isometry3d>> truth_world;
  for (int id : seen_ids) {
    for (const RealFrame& f : seq.frames) {
      const auto o = std::find_if(f.objects.begin(), f.objects.end(),
                                  [&](const RealObjectTruth& t) { return t.obj_id == id; });
      if (o == f.objects.end()) continue;
      truth_world.emplace_back(names[id], f.T_world_cam * o->T_cam_obj);
      break;
    }
  }
  run.objects = static_cast<int>(truth_world.size());
  std::vector<bool> used(final_map.objects.size(), false);
  for (const auto& [name, T] : truth_world) {
    double best = 1e9;
    int best_k = -1;
    for (std::size_t k = 0; k < final_map.objects.size(); ++k) {
      const ObjectEstimate& o = final_map.objects[k];
      if (used[k] || o.model->name != name) continue;
      const double d = (o.T_map_obj.translation() - T.translation()).norm();
      if (d < best) best = d, best_k = static_cast<int>(k);
    }
    char line[160];
    if (best_k < 0) {
      std::snprintf(line, sizeof(line), "%s: not mapped", name.c_str());
    } else {
      std::snprintf(line, sizeof(line), "%s: %.1f mm from the truth", name.c_str(), 1000.0 * best);
    }
    run.report.push_back(line);
    if (best_k >= 0 && best < 0.02) {
      ++run.mapped;
      used[best_k] = true;
    }
  }
  for (std::size_t k = 0; k < final_map.objects.size(); ++k) {
    if (!used[k]) {
      ++run.false_objects;
      run.report.push_back("false object: " + final_map.objects[k].model->name);
    }
  }
  return run;
}

TEST(RealYcbVideo, AlongRayBiasRefinedAwayEveryObjectMapped) {
  const std::string dir = realDir() + "/ycbv_video";
  if (!std::ifstream(dir + "/0000/scene_camera.json").good()) {
    GTEST_SKIP() << "real YCB-Video frames not found at " << dir;
  }
  if (!test::haveYcb()) GTEST_SKIP() << "YCB-Video models not found at " << test::ycbDir();
  ModelSet models;
  std::vector<std::string> errors;
  ASSERT_TRUE(test::loadYcbModels(&models, &errors));
  std::vector<double> before, after;
  for (const char* video : {"0000", "0001"}) {
    const VideoRun run = runVideo(dir + "/" + video, models);
    before.insert(before.end(), run.ray_error_before_m.begin(), run.ray_error_before_m.end());
    after.insert(after.end(), run.ray_error_after_m.begin(), run.ray_error_after_m.end());
    std::string report;
    for (const std::string& line : run.report) report += "\n  " + line;
    std::printf(
        "[ real ] video %s: %d detections, %d refined; median |along-ray error| %.1f mm "
        "-> %.2f mm; %d of %d objects mapped within 2 cm, %d false%s\n",
        video, run.detections, run.refined, 1000.0 * median(run.ray_error_before_m),
        1000.0 * median(run.ray_error_after_m), run.mapped, run.objects, run.false_objects,
        report.c_str());
    EXPECT_GT(run.objects, 2) << video;
    EXPECT_EQ(run.mapped, run.objects) << video << report;
    EXPECT_EQ(run.false_objects, 0) << video << report;
  }
  ASSERT_FALSE(after.empty());
  EXPECT_GT(median(before), 0.02);  // the bias is there
  EXPECT_LT(median(after), 0.002);
}

std::string describe(const DepthStatistics& s) {
  std::string out;
  char buf[200];
  for (std::size_t b = 0; b < s.bin_upper_m.size(); ++b) {
    std::snprintf(buf, sizeof(buf), "below %.1f m: %.2f mm (%ld px); ", s.bin_upper_m[b],
                  1000.0 * s.median_abs_residual_m[b], s.bin_pixels[b]);
    out += buf;
  }
  std::snprintf(buf, sizeof(buf),
                "holes: objects %.2f %%, within 3 px of edges %.1f %%, left / right of objects "
                "%.1f / %.1f %%; edge error band %.2f px",
                100.0 * s.object_invalid, 100.0 * s.edge_invalid, 100.0 * s.left_of_objects_invalid,
                100.0 * s.right_of_objects_invalid, s.edge_band_px);
  return out + buf;
}

/// Within a factor `f` of each other (both tiny counts as agreeing).
bool withinFactor(double a, double b, double f, double tiny) {
  if (a < tiny && b < tiny) return true;
  return a <= f * b && b <= f * a;
}

// The Fetch head camera's model (structured light) against the real Xtion: the same frames'
// clean depth (the ground truth rendered on objects, the real background) through the model
// gives the statistics of the real depth within a factor 1.5.
TEST(RealYcbVideo, StructuredLightModelMatchesTheXtion) {
  const std::string dir = realDir() + "/ycbv_video";
  if (!std::ifstream(dir + "/0000/scene_camera.json").good()) {
    GTEST_SKIP() << "real YCB-Video frames not found at " << dir;
  }
  if (!test::haveYcb()) GTEST_SKIP() << "YCB-Video models not found at " << test::ycbDir();
  ModelSet models;
  std::vector<std::string> errors;
  ASSERT_TRUE(test::loadYcbModels(&models, &errors));
  OffscreenRenderer renderer;
  ASSERT_TRUE(renderer.ok()) << renderer.error();
  std::map<const ObjectModel*, MeshHandle> meshes;
  DepthStatisticsAccumulator real_stats, model_stats, earlier_stats;
  const DepthNoise sensor = DepthNoise::structuredLight();
  std::mt19937 rng(5);
  for (const char* video : {"0000", "0001"}) {
    RealSequence seq;
    std::string error;
    ASSERT_TRUE(readRealSequence(dir + "/" + video, "auto", 30.0, &seq, &error)) << error;
    for (const RealFrame& f : seq.frames) {
      std::vector<RenderItem> items;
      std::vector<SurfaceMaterial> material_of(1, SurfaceMaterial::kDiffuse);
      for (const RealObjectTruth& o : f.objects) {
        const ObjectModel* model = models.findById(o.obj_id);
        ASSERT_NE(model, nullptr) << o.obj_id;
        if (!meshes.count(model)) meshes[model] = renderer.addMesh(model->mesh);
        RenderItem item;
        item.mesh = meshes[model];
        item.T_cam_model = o.T_cam_obj;
        item.instance_id = static_cast<std::uint16_t>(items.size() + 1);
        items.push_back(item);
        material_of.push_back(model->material);
      }
      RenderedImages rendered;
      ASSERT_TRUE(renderer.render(f.K, items, &rendered)) << renderer.error();
      std::vector<float> real;
      int w = 0, h = 0;
      ASSERT_TRUE(loadDepthMetres(f, &real, &w, &h, &error)) << error;
      const std::vector<float> clean = cleanDepthOf(f.K, real, rendered.depth, rendered.instance);
      std::vector<float> simulated = clean;
      applyDepthNoise(f.K, sensor, rng, &simulated, &rendered.instance, &material_of);
      real_stats.add(f.K, real, clean, rendered.instance);
      if (std::getenv("GEOFUSION_CLASS_HOLES")) {
        for (std::size_t k = 0; k < items.size(); ++k) {
          long n = 0, holes = 0;
          for (std::size_t i = 0; i < real.size(); ++i) {
            if (rendered.instance[i] != k + 1) continue;
            ++n;
            holes += !(real[i] > 0.f);
          }
          std::printf("%s %s %s: %.1f %% of %ld\n", video, f.name.c_str(),
                      models.findById(f.objects[k].obj_id)->name.c_str(), 100.0 * holes / n, n);
        }
      }
      model_stats.add(f.K, simulated, clean, rendered.instance);
      std::vector<float> earlier = clean;  // the generator's model before issue 31, for the docs
      applyDepthNoise(f.K, DepthNoise::nguyen2012(), rng, &earlier);
      earlier_stats.add(f.K, earlier, clean, rendered.instance);
    }
  }
  const DepthStatistics r = real_stats.result(), m = model_stats.result();
  std::printf(
      "[ real ] Xtion (15 YCB-Video frames): %s\n[ model] structured_light:        %s\n"
      "[ model] nguyen2012 (earlier):      %s\n",
      describe(r).c_str(), describe(m).c_str(), describe(earlier_stats.result()).c_str());
  int compared_bins = 0;
  for (std::size_t b = 0; b < r.bin_upper_m.size(); ++b) {
    if (r.bin_pixels[b] < 5000 || m.bin_pixels[b] < 5000) continue;
    ++compared_bins;
    EXPECT_TRUE(withinFactor(r.median_abs_residual_m[b], m.median_abs_residual_m[b], 1.5, 0.0))
        << "residual below " << r.bin_upper_m[b] << " m";
  }
  EXPECT_GE(compared_bins, 2);
  EXPECT_TRUE(withinFactor(r.object_invalid, m.object_invalid, 1.5, 0.005)) << "object holes";
  EXPECT_TRUE(withinFactor(r.edge_invalid, m.edge_invalid, 1.5, 0.005)) << "edge holes";
  EXPECT_TRUE(withinFactor(r.edge_band_px, m.edge_band_px, 1.5, 0.0)) << "edge band";
  EXPECT_TRUE(withinFactor(r.left_of_objects_invalid, m.left_of_objects_invalid, 1.5, 0.01))
      << "the shadow's side";
  EXPECT_TRUE(withinFactor(r.right_of_objects_invalid, m.right_of_objects_invalid, 1.5, 0.01))
      << "the side without a shadow";
}

TEST(Real7Scenes, VisualOdometryTracksEveryFrame) {
  const std::string dir = realDir() + "/7scenes_redkitchen";
  if (!std::ifstream(dir + "/frame-000000.depth.png").good()) {
    GTEST_SKIP() << "real 7-Scenes frames not found at " << dir;
  }
  RealSequence seq;
  std::string error;
  ASSERT_TRUE(readRealSequence(dir, "auto", 30.0, &seq, &error)) << error;
  EXPECT_EQ(seq.format, "7scenes");
  ASSERT_EQ(seq.frames.size(), 300u);
  VisualOdometry vo;
  std::vector<double> stamps, true_stamps, times;
  std::vector<Eigen::Isometry3d> est, truth;
  int lost = 0;
  for (const RealFrame& f : seq.frames) {
    std::vector<std::uint8_t> gray;
    std::vector<float> depth;
    int w = 0, h = 0, dw = 0, dh = 0;
    ASSERT_TRUE(loadGray(f, &gray, &w, &h, &error)) << error;
    ASSERT_TRUE(loadDepthMetres(f, &depth, &dw, &dh, &error)) << error;
    ASSERT_EQ(w, dw);
    const VoFrameResult r = vo.track(GrayImageView{gray.data(), w, h, w},
                                     DepthImageView{depth.data(), dw, dh}, f.K, f.stamp_s);
    ASSERT_TRUE(f.has_camera_pose);
    true_stamps.push_back(f.stamp_s);
    truth.push_back(f.T_world_cam);
    if (!r.pose_valid) {
      ++lost;
      continue;
    }
    stamps.push_back(f.stamp_s);
    est.push_back(r.T_odom_cam);
    times.push_back(r.time_ms);
  }
  const TrajectoryErrors e = trajectoryErrors(stamps, est, true_stamps, truth);
  std::printf(
      "[ real ] 7-Scenes redkitchen: %zu frames, %d lost, ATE %.2f cm over %.2f m, "
      "median %.1f ms a frame\n",
      seq.frames.size(), lost, 100.0 * e.ate_rmse_m, e.length_m, median(times));
  EXPECT_EQ(lost, 0);
  EXPECT_GT(e.length_m, 1.5);
  // Measured 1.88 cm (2.84 before keyframes shared landmarks; docs/visual_odometry.md, "Real
  // frames"); the same frames from later or at 15 Hz give 2.07-2.37 cm. The bound leaves room for
  // a different OpenCV build's features, not for the regression back to 2.84 cm.
  EXPECT_LT(e.ate_rmse_m, 0.026);
}

}  // namespace
}  // namespace geofusion
