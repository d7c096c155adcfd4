// The scene estimator on a generated bench-like sequence, all four methods: per-stage time a
// keyframe (p50 / p95 / max, one core) and the final map against ground truth. A benchmark that
// prints figures, not a test; the full benchmark (COCO mAP, ADD-S curves, contacts) is the
// benchmark tool's.
//
//   estimator_benchmark [--models DIR] [--objects 18] [--keyframes 100] [--seed 101]
//                       [--detector PRESET] [--method NAME] [--threads N]
//                       [--render-triangles N] [--render-error M] (and the others of docs/tools.md)
//
// DIR holds the YCB-Video models (default ../shared/data/ycb_video beside the source tree);
// without them the built-in primitives are used and the output says so.
#include "geofusion/common/statistics.h"
#include "geofusion/config/config.h"
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/evaluation/evaluation.h"
#include "geofusion/evaluation/metrics.h"
#include "geofusion/evaluation/sequence_calibration.h"
#include "geofusion/render/renderer.h"
#include "geofusion/simulation/dataset.h"
#include "model_set_option.h"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

using namespace geofusion;

struct Options {
  std::string models_dir = defaultYcbDir("estimator_benchmark");
  int objects = 18, keyframes = 100;
  unsigned seed = 101;
  std::string detector = "densefusion", only;
  ConsistencyConfig consistency;
  AssociationConfig association;
  std::string params;  ///< --params: the estimator's settings from this configuration file
};

// False, the usage printed, on an option it does not know.
bool parse(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--method" && i + 1 < argc) {
      o->only = argv[++i];
    } else if (a == "--eps-res" && i + 1 < argc) {
      o->consistency.eps_res = std::atof(argv[++i]);
    } else if (a == "--eps-out" && i + 1 < argc) {
      o->consistency.eps_out = std::atof(argv[++i]);
    } else if (a == "--inlier-centre" && i + 1 < argc) {
      o->consistency.inlier.centre = std::atof(argv[++i]);
    } else if (a == "--outlier-centre" && i + 1 < argc) {
      o->consistency.outlier.centre = std::atof(argv[++i]);
    } else if (a == "--threads" && i + 1 < argc) {
      o->consistency.threads = std::atoi(argv[++i]);
    } else if (a == "--render-triangles" && i + 1 < argc) {
      o->consistency.render_mesh_triangles = std::atoi(argv[++i]);
    } else if (a == "--render-error" && i + 1 < argc) {
      o->consistency.render_mesh_max_error_m = std::atof(argv[++i]);
    } else if (a == "--eps-fp" && i + 1 < argc) {
      o->association.eps_fp = std::atof(argv[++i]);
    } else if (a == "--eps-new" && i + 1 < argc) {
      o->association.eps_new = std::atof(argv[++i]);
    } else if (a == "--models" && i + 1 < argc) {
      o->models_dir = argv[++i];
    } else if (a == "--objects" && i + 1 < argc) {
      o->objects = std::atoi(argv[++i]);
    } else if (a == "--keyframes" && i + 1 < argc) {
      o->keyframes = std::atoi(argv[++i]);
    } else if (a == "--seed" && i + 1 < argc) {
      o->seed = static_cast<unsigned>(std::atoi(argv[++i]));
    } else if (a == "--detector" && i + 1 < argc) {
      o->detector = argv[++i];
    } else if (a == "--params" && i + 1 < argc) {
      o->params = argv[++i];
    } else {
      std::fprintf(
          stderr,
          "usage: %s [--models DIR] [--objects N] [--keyframes N] [--seed S] "
          "[--detector PRESET] [--method NAME] [--params FILE] [--eps-res M] [--eps-out M] "
          "[--inlier-centre X] [--outlier-centre X] [--eps-fp X] [--eps-new X] "
          "[--threads N] [--render-triangles N] [--render-error M]\n",
          argv[0]);
      return false;
    }
  }
  return true;
}

// The YCB-Video models of `models_dir`, else the built-in primitives (and the output says so);
// true for the YCB-Video models.
bool loadModels(const std::string& models_dir, ModelSet* models) {
  std::vector<std::string> errors;
  const bool ycb =
      ModelSet::load(requirePackageDir("estimator_benchmark") + "/config/models/ycb_video.yaml",
                     models_dir, models, &errors) &&
      models->size() > 0;
  if (!ycb) {
    *models = ModelSet::builtinPrimitives();
    std::printf("YCB-Video models not found in %s: using the built-in primitives\n",
                models_dir.c_str());
  }
  return ycb;
}

/// The benchmark's sequence: a bench-like scene and its keyframes, rendered.
struct Sequence {
  ClutterScene scene;
  unsigned used = 0;  ///< the seed the scene settled with
  std::vector<FramePose> poses;
  std::vector<SequenceFrame> frames;
  PinholeIntrinsics K;
};

// False, having said why, when the scene cannot be made.
bool makeSequence(const Options& o, const SuiteSpec& suite, const ModelSet& models, Sequence* seq) {
  SceneSpec spec{"benchmark", o.seed, o.objects};
  std::string report;
  if (!makeSuiteScene(suite, spec, models, &seq->scene, &seq->used, &report)) {
    std::fprintf(stderr, "scene: %s\n", report.c_str());
    return false;
  }
  TrajectoryConfig traj = suite.trajectory;
  traj.frames = o.keyframes;
  traj.rate_hz = 5.0;
  seq->poses = makeTrajectory(seq->scene, traj, o.seed);
  addOdometryDrift(&seq->poses, suite.odometry, o.seed + 1000);
  SequenceRenderer renderer(seq->scene, seq->K);
  std::mt19937 rng(o.seed + 2000);
  for (const FramePose& p : seq->poses)
    seq->frames.push_back(renderer.render(p, suite.depth, suite.detector, models, rng));
  return true;
}

// The scene, its detections and the frame-by-frame reference.
void printSequence(const Options& o, const Sequence& seq, bool ycb) {
  int detections = 0;
  for (const auto& f : seq.frames) detections += static_cast<int>(f.detections.size());
  std::printf("scene: %zu %s objects (seed %u), %d keyframes, %.1f detections a keyframe (%s)\n",
              seq.scene.objects.size(), ycb ? "YCB-Video" : "primitive", seq.used, o.keyframes,
              static_cast<double>(detections) / o.keyframes, o.detector.c_str());
  std::printf("objects detected (true class) in >= 5 keyframes: %d\n\n",
              objectsDetectedInFrames(seq.scene, seq.frames, 5));

  // FbF reference: each keyframe's true-class detections.
  SequenceCalibration fbf_calibration;
  for (std::size_t k = 0; k < seq.frames.size(); ++k)
    fbf_calibration.add(seq.scene, seq.poses[k].T_map_optical, seq.frames[k]);
  const std::vector<double> fbf = fbf_calibration.errors();
  std::printf(
      "FbF (per keyframe, true detections): ADD-S mean %.2f mm, < 1 cm %.1f %%, < 2 cm %.1f %%\n\n",
      1000.0 *
          [&] {
            double s = 0;
            for (double e : fbf) s += e;
            return s / std::max<std::size_t>(1, fbf.size());
          }(),
      100.0 * shareBelow(fbf, 0.01), 100.0 * shareBelow(fbf, 0.02));
}

/// Each keyframe's time by stage, ms.
struct StageTimes {
  std::vector<double> consistency, association, lifecycle, stage_one, relations, stage_two, total;

  void add(const StageTimings& t) {
    consistency.push_back(t.consistency_ms);
    association.push_back(t.association_ms);
    lifecycle.push_back(t.lifecycle_ms);
    stage_one.push_back(t.stage_one_ms);
    relations.push_back(t.relations_ms);
    stage_two.push_back(t.stage_two_ms);
    total.push_back(t.total_ms);
  }

  /// p50/p95/max of each stage: the table's last column.
  std::string column() const {
    std::string times;
    char buf[64];
    for (const auto* v :
         {&consistency, &association, &lifecycle, &stage_one, &relations, &stage_two, &total}) {
      std::snprintf(buf, sizeof(buf), "%.1f/%.1f/%.1f  ", percentile(*v, 0.5), percentile(*v, 0.95),
                    percentile(*v, 1.0));
      times += buf;
    }
    return times;
  }
};

// What the map's false objects are: the nearest true object of their class, if any.
void printMapObjects(const ClutterScene& scene, const KeyframeResult& final) {
  for (std::size_t k = 0; k < final.objects.size(); ++k) {
    const auto& o = final.objects[k];
    double best = 1e9;
    int nearest = -1;
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
      const auto& t = scene.objects[i];
      if (t.model->name != o.model->name) continue;
      const double e = addsError(o.model->points, o.T_map_obj, t.T_world_obj);
      if (e < best) best = e, nearest = static_cast<int>(i);
    }
    std::printf("  map object %d: %s, n %d, R %.2f, nearest true of its class #%d at %.1f mm\n",
                o.id, o.model->name.c_str(), o.measurements, o.best_consistency, nearest,
                best > 1e8 ? -1.0 : 1000 * best);
  }
}

// Which true objects the map lacks, and how consistent their detections were
// (`object_consistency`: of each true object).
void printMissedObjects(const ClutterScene& scene, const KeyframeResult& final,
                        const std::vector<std::vector<double>>& object_consistency) {
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    bool found = false;
    for (const auto& o : final.objects)
      found |= o.model->name == scene.objects[i].model->name &&
               addsError(o.model->points, o.T_map_obj, scene.objects[i].T_world_obj) < 0.05;
    if (found) continue;
    const auto& c = object_consistency[i];
    double mx = 0, mean = 0;
    for (double v : c) mx = std::max(mx, v), mean += v / std::max<std::size_t>(1, c.size());
    std::printf("  not in the map: %s, %zu detections, f_gc mean %.2f max %.2f\n",
                scene.objects[i].model->name.c_str(), c.size(), mean, mx);
    for (const auto& o : final.objects) {
      if (o.model->name != scene.objects[i].model->name) continue;
      std::printf("    map has one %.1f mm ADD-S away (n %d, R %.2f)\n",
                  1000 * addsError(o.model->points, o.T_map_obj, scene.objects[i].T_world_obj),
                  o.measurements, o.best_consistency);
    }
  }
}

// One method over the sequence: its row of the table (for GeoFusion also what its map got right
// and wrong).
void benchmarkMethod(Method method, const Options& opts, const ModelSet& models,
                     const Sequence& seq, const std::shared_ptr<OffscreenRenderer>& shared) {
  const ClutterScene& scene = seq.scene;
  EstimatorConfig config;
  config.consistency = opts.consistency;
  config.association = opts.association;
  if (!opts.params.empty()) {  // the file's estimator settings (of the flags, --threads only)
    GeoFusionConfig file;
    ConfigReport report;
    loadConfigFile(opts.params, &file, &report);
    for (const std::string& e : report.errors)
      std::fprintf(stderr, "estimator_benchmark: %s\n", e.c_str());
    if (!report.ok()) std::exit(2);
    config = file.estimator;
    config.consistency.threads = opts.consistency.threads;
  }
  config.method = method;
  SceneEstimator estimator(models, config, shared);
  estimator.prepare();  // as the node does when the model set loads: no first-use cost timed
  StageTimes timings;
  std::vector<std::vector<double>> object_consistency(scene.objects.size());
  for (std::size_t k = 0; k < seq.frames.size(); ++k) {
    const KeyframeResult r =
        estimator.addKeyframe(makeKeyframe(seq.poses[k], seq.frames[k], seq.K));
    for (std::size_t d = 0; d < r.detections.size() && d < seq.frames[k].detection_truth.size();
         ++d) {
      const int t = seq.frames[k].detection_truth[d];
      if (t >= 0)
        object_consistency[static_cast<std::size_t>(t)].push_back(r.detections[d].consistency);
    }
    timings.add(r.timings);
  }
  const KeyframeResult final = estimator.finish();
  const std::string times = timings.column();
  if (stagesOf(method).map_is_keyframe_detections) {
    std::printf("%-10s %7s %5s %5s %9s %7s %7s | %s\n", toString(method), "-", "-", "-", "-", "-",
                "-", times.c_str());
    return;
  }
  const MapScore s = scoreMap(scene, final.objects);
  if (method == Method::kGeoFusion) printMapObjects(scene, final);
  if (method == Method::kGeoFusion && s.true_positives < static_cast<int>(scene.objects.size()))
    printMissedObjects(scene, final, object_consistency);
  std::printf("%-10s %7d %5d %5d %9.2f %7.1f %7.1f | %s\n", toString(method), s.objects,
              s.true_positives, s.false_positives, 1000 * s.mean_adds_m,
              100 * shareBelow(s.adds_m, 0.01), 100 * shareBelow(s.adds_m, 0.02), times.c_str());
  if (method == Method::kGeoFusion) {
    std::printf(
        "GeoFusion final map: %zu contacts, support plane %s at %.3f m; final solve %.1f ms "
        "(stage II and the physical check %.1f ms)\n",
        final.contacts.size(), estimator.supportPlane().valid ? "found" : "not found",
        estimator.supportPlane().height, final.timings.total_ms, final.timings.stage_two_ms);
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse(argc, argv, &o)) return 2;
  ModelSet models;
  const bool ycb = loadModels(o.models_dir, &models);
  SuiteSpec suite;
  suiteByName("bench", &suite);
  if (!DetectorModel::byName(o.detector, &suite.detector)) {
    std::fprintf(stderr, "unknown detector preset '%s'\n", o.detector.c_str());
    return 2;
  }
  Sequence seq;
  if (!makeSequence(o, suite, models, &seq)) return 1;
  printSequence(o, seq, ycb);

  std::printf("%-10s %7s %5s %5s %9s %7s %7s | ms a keyframe p50/p95/max: %s\n", "method",
              "objects", "true", "false", "ADD-S mm", "<1cm %", "<2cm %",
              "consistency  association  lifecycle  stage I  relations  stage II  total");
  auto shared = std::make_shared<OffscreenRenderer>();
  for (Method method : {Method::kFrameByFrame, Method::kFrameByFrameRefined, Method::kBaselineSlam,
                        Method::kRobustFrontEnd, Method::kGeoFusion}) {
    Method wanted;
    if (!o.only.empty() && parseMethod(o.only, &wanted) && wanted != method) continue;
    benchmarkMethod(method, o, models, seq, shared);
  }
  struct rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  std::printf("peak memory %.0f MB\n", usage.ru_maxrss / 1024.0);
  return 0;
}
