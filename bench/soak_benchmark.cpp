// soak_benchmark: GeoFusion on a long run (issue 22). A robot visits several tables of clutter in
// turn and comes back to each (revisits after hundreds of keyframes), every keyframe rendered on
// the fly (no recording on disk); per keyframe its time by stage and the process's resident
// memory go to a CSV, and a summary compares the start of the run with its end. bench/plot_soak.py
// plots the CSV; `make soak` runs both. A benchmark that prints figures, not a test.
//
//   soak_benchmark --out soak.csv [--keyframes 2000] [--tables 3] [--visit 100] [--objects 20]
//                  [--seed 7] [--detector densefusion_persistent] [--bias-scale 1]
//                  [--models DIR] [--params FILE] [--set KEY=VALUE]...
//
// --bias-scale multiplies the detector's persistent errors (bias, error along the ray, phantoms,
// swapped and missed stretches): 0 gives the same run with independent errors only.
//
// DIR holds the YCB-Video models (default ../shared/data/ycb_video beside the source tree);
// without them the built-in primitives are used and the output says so.
#include "command_line.h"
#include "config_option.h"
#include "geofusion/common/statistics.h"
#include "geofusion/config/config.h"
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/evaluation/evaluation.h"
#include "geofusion/render/renderer.h"
#include "geofusion/simulation/dataset.h"
#include "model_set_option.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace {

using namespace geofusion;

struct Options {
  std::string out, models_dir = defaultYcbDir("soak_benchmark");
  ConfigOptions config;  ///< --params, --set
  int keyframes = 2000, tables = 3, visit = 100, objects = 20;
  unsigned seed = 7;
  std::string detector = "densefusion_persistent";
  double bias_scale = 1.0;
};

void usage() {
  std::printf(
      "usage: soak_benchmark --out soak.csv [--keyframes 2000] [--tables 3] [--visit 100]\n"
      "                      [--objects 20] [--seed 7] [--detector densefusion_persistent]\n"
      "                      [--bias-scale 1] [--models DIR] [--params FILE] [--set "
      "KEY=VALUE]...\n");
}

// Resident memory of this process, MB (/proc/self/statm).
double residentMb() {
  std::ifstream statm("/proc/self/statm");
  long pages = 0, resident = 0;
  statm >> pages >> resident;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / 1048576.0;
}

// Where table t stands in the map: 4 m apart along x, each turned a little.
Eigen::Isometry3d tablePlacement(int t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(4.0 * t, 0.0, 0.0);
  T.linear() = Eigen::AngleAxisd(0.7 * t, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T;
}

// One keyframe of the run: the table it looks at, its pose in that table's scene (for rendering)
// and in the map (for the estimator, odometry drifting over the whole run).
struct RunFrame {
  int table = 0, visit = 0;
  FramePose scene_pose, map_pose;
};

std::vector<RunFrame> makeRun(const Options& o, const SuiteSpec& suite,
                              const std::vector<ClutterScene>& scenes) {
  std::vector<RunFrame> run;
  std::vector<FramePose> map_poses;
  double stamp = 0.0;
  for (int visit = 0; static_cast<int>(run.size()) < o.keyframes; ++visit) {
    const int t = visit % o.tables;
    TrajectoryConfig traj = suite.trajectory;
    traj.frames = std::min(o.visit, o.keyframes - static_cast<int>(run.size()));
    traj.rate_hz = 5.0;
    for (const FramePose& p : makeTrajectory(scenes[static_cast<std::size_t>(t)], traj,
                                             o.seed + 100 * static_cast<unsigned>(visit))) {
      RunFrame f;
      f.table = t, f.visit = visit;
      f.scene_pose = p;
      f.map_pose = p;
      const Eigen::Isometry3d T = tablePlacement(t);
      f.map_pose.stamp_s = stamp + p.stamp_s;
      f.map_pose.T_map_base = T * p.T_map_base;
      f.map_pose.T_map_optical = T * p.T_map_optical;
      f.map_pose.T_odom_base = f.map_pose.T_map_base;
      run.push_back(f);
      map_poses.push_back(f.map_pose);
    }
    stamp = map_poses.back().stamp_s + 15.0;  // the drive to the next table
  }
  addOdometryDrift(&map_poses, suite.odometry, o.seed + 1000);
  for (std::size_t k = 0; k < run.size(); ++k) run[k].map_pose = map_poses[k];
  return run;
}

// The detector's persistent errors times `k` (k = 0: independent errors only).
void scalePersistentErrors(PersistentErrorModel* p, double k) {
  p->bias_translation_m *= k;
  p->bias_rotation_rad *= k;
  p->ray_depth_fraction *= k;
  p->swap_stretch_rate *= k;
  p->miss_stretch_rate *= k;
  p->phantoms = static_cast<int>(std::lround(k * p->phantoms));
}

// p95 of the total time over keyframes [from, to).
double p95(const std::vector<double>& ms, std::size_t from, std::size_t to) {
  to = std::min(to, ms.size());
  if (from >= to) return 0.0;
  return percentile(
      std::vector<double>(ms.begin() + static_cast<long>(from), ms.begin() + static_cast<long>(to)),
      0.95);
}

// The options into `o`; throws on a missing or wrong one.
void parse(int argc, char** argv, Options* o) {
  CommandLine args;
  args.value("--out", &o->out);
  args.value("--keyframes", &o->keyframes);
  args.value("--tables", &o->tables);
  args.value("--visit", &o->visit);
  args.value("--objects", &o->objects);
  args.value("--seed", &o->seed);
  args.value("--models", &o->models_dir);
  args.value("--detector", &o->detector);
  args.value("--bias-scale", &o->bias_scale);
  o->config.declare(&args);
  args.parse(argc, argv, usage);
  if (o->out.empty()) throw std::runtime_error("--out needed");
  if (o->keyframes < 1 || o->tables < 1 || o->visit < 1 || o->objects < 1)
    throw std::runtime_error("--keyframes, --tables, --visit and --objects must be positive");
  if (!(o->bias_scale >= 0.0)) throw std::runtime_error("--bias-scale must be >= 0");
}

// The YCB-Video models of o.models_dir, else the built-in primitives (and the output says so);
// true for the YCB-Video models.
bool loadModels(const Options& o, const GeoFusionConfig& config, ModelSet* models) {
  std::vector<std::string> errors;
  const bool ycb =
      ModelSet::load(requirePackageDir("soak_benchmark") + "/config/models/ycb_video.yaml",
                     o.models_dir, models, &errors, config.model_set.surface_features) &&
      models->size() > 0;
  if (!ycb) {
    *models = ModelSet::builtinPrimitives();
    std::printf("YCB-Video models not found in %s: using the built-in primitives\n",
                o.models_dir.c_str());
  }
  return ycb;
}

// The tables' scenes, settled. False, having said why, when one cannot be made.
bool makeScenes(const Options& o, const SuiteSpec& suite, const ModelSet& models,
                std::vector<ClutterScene>* scenes) {
  scenes->resize(static_cast<std::size_t>(o.tables));
  for (int t = 0; t < o.tables; ++t) {
    SceneSpec spec{"soak_table_" + std::to_string(t), o.seed + 17 * static_cast<unsigned>(t),
                   o.objects};
    unsigned used = 0;
    std::string why;
    if (!makeSuiteScene(suite, spec, models, &(*scenes)[static_cast<std::size_t>(t)], &used,
                        &why)) {
      std::cerr << "soak_benchmark: table " << t << ": " << why << "\n";
      return false;
    }
  }
  return true;
}

/// What the run measured.
struct SoakRecord {
  std::vector<double> total_ms, rss_mb;  ///< per keyframe
  int relocalisations = 0;
  double wall_s = 0.0;  ///< rendering included
};

// The run through the estimator, every keyframe rendered on the fly; per keyframe its time by
// stage and the resident memory into the CSV and `record`. Returns the final map.
KeyframeResult runKeyframes(const Options& o, const GeoFusionConfig& config, const SuiteSpec& suite,
                            const ModelSet& models, const std::vector<RunFrame>& run,
                            const std::vector<std::unique_ptr<SequenceRenderer>>& renderers,
                            const PinholeIntrinsics& K, std::ostream* csv, SoakRecord* record) {
  SceneEstimator estimator(models, config.estimator);
  std::mt19937 rng(o.seed + 2000);
  *csv << "keyframe,table,visit,detections,objects,tentative,consistency_ms,association_ms,"
          "lifecycle_ms,stage_one_ms,"
          "relations_ms,stage_two_ms,total_ms,rss_mb,relocalised\n";
  std::vector<double>& total_ms = record->total_ms;
  std::vector<double>& rss_mb = record->rss_mb;
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t k = 0; k < run.size(); ++k) {
    const RunFrame& f = run[k];
    const SequenceFrame frame = renderers[static_cast<std::size_t>(f.table)]->render(
        f.scene_pose, suite.depth, suite.detector, models, rng);
    const KeyframeResult r = estimator.addKeyframe(makeKeyframe(f.map_pose, frame, K));
    total_ms.push_back(r.timings.total_ms);
    rss_mb.push_back(residentMb());
    *csv << k << ',' << f.table << ',' << f.visit << ',' << frame.detections.size() << ','
         << r.objects.size() << ',' << r.tentative.size() << ',' << r.timings.consistency_ms << ','
         << r.timings.association_ms << ',' << r.timings.lifecycle_ms << ','
         << r.timings.stage_one_ms << ',' << r.timings.relations_ms << ',' << r.timings.stage_two_ms
         << ',' << r.timings.total_ms << ',' << rss_mb.back() << ','
         << (r.relocalisation.applied ? 1 : 0) << '\n';
    record->relocalisations += r.relocalisation.applied;
    if ((k + 1) % 100 == 0) {
      std::printf("  keyframe %zu: %zu objects, p95 of the last 100 %.1f ms, %.0f MB\n", k + 1,
                  r.objects.size(), p95(total_ms, k + 1 - 100, k + 1), rss_mb.back());
      std::fflush(stdout);
    }
  }
  KeyframeResult final = estimator.finish();
  record->wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return final;
}

// The final map against each table's objects (placed in the map). A map object belongs to the
// table the robot looked at when the map first held it (its first keyframe), wherever the drift
// put it; each table is scored in the world frame (the drift shows) and aligned on its own
// (alignMapToScene: by class, with no starting guess, so that any drift is searched).
void printMapScores(const Options& o, const std::vector<ClutterScene>& scenes,
                    const std::vector<RunFrame>& run, const KeyframeResult& final,
                    int relocalisations) {
  std::printf("final map: %zu objects; the camera relocalised against the map %d times\n",
              final.objects.size(), relocalisations);
  std::vector<std::vector<ObjectEstimate>> of_table(static_cast<std::size_t>(o.tables));
  int unplaced = 0;
  for (const auto& e : final.objects) {
    if (e.first_keyframe < 0 || e.first_keyframe >= static_cast<int>(run.size())) {
      ++unplaced;
      continue;
    }
    of_table[static_cast<std::size_t>(run[static_cast<std::size_t>(e.first_keyframe)].table)]
        .push_back(e);
  }
  if (unplaced) std::printf("  %d objects without a first keyframe in the run\n", unplaced);
  int total_true = 0, total_tp = 0, total_fp = 0;
  double total_adds = 0.0;
  for (int t = 0; t < o.tables; ++t) {
    ClutterScene placed = scenes[static_cast<std::size_t>(t)];
    for (auto& obj : placed.objects) obj.T_world_obj = tablePlacement(t) * obj.T_world_obj;
    std::vector<ObjectEstimate> objects = of_table[static_cast<std::size_t>(t)];
    const MapScore s = scoreMap(placed, objects);
    const SceneAlignment a = alignMapToScene(placed, objects);
    for (auto& e : objects) e.T_map_obj = a.T_true_map * e.T_map_obj;
    const MapScore aligned = scoreMap(placed, objects);
    // The drift at the table: where its centre is in the map, and the turn.
    const Eigen::Vector3d centre = tablePlacement(t).translation();
    const double offset = (a.T_true_map.inverse() * centre - centre).norm();
    const double turn = Eigen::AngleAxisd(a.T_true_map.linear()).angle();
    std::printf(
        "  table %2d: %zu true objects; map %d there: in the world frame %d true, %d false, ADD-S "
        "%.1f mm; aligned (%d objects agree, %.1f cm rmse; the map %.2f m and %.1f deg off there) "
        "%d true, %d false, ADD-S %.1f mm\n",
        t, placed.objects.size(), s.objects, s.true_positives, s.false_positives,
        1000 * s.mean_adds_m, a.inliers, 100 * a.rmse_m, offset, turn * 180.0 / M_PI,
        aligned.true_positives, aligned.false_positives, 1000 * aligned.mean_adds_m);
    total_true += static_cast<int>(placed.objects.size());
    total_tp += aligned.true_positives;
    total_fp += aligned.false_positives;
    total_adds += aligned.mean_adds_m * aligned.true_positives;
  }
  std::printf("  every table aligned: %d of %d true objects found, %d false, ADD-S %.1f mm\n",
              total_tp, total_true, total_fp, total_tp ? 1000 * total_adds / total_tp : 0.0);
}

// The time a keyframe and the memory early in the run and at its end.
void printTimes(const Options& o, const SoakRecord& record) {
  const std::vector<double>& total_ms = record.total_ms;
  const std::vector<double>& rss_mb = record.rss_mb;
  const std::size_t n = total_ms.size();
  const std::size_t early_from = std::min<std::size_t>(100, n),
                    early_to = std::min<std::size_t>(200, n);
  std::printf(
      "time a keyframe: p95 %.1f ms over keyframes %zu-%zu, %.1f ms over the last 100 (%zu-%zu); "
      "total %.0f s for %zu keyframes (rendering included)\n",
      p95(total_ms, early_from, early_to), early_from, early_to,
      p95(total_ms, n - std::min<std::size_t>(100, n), n), n - std::min<std::size_t>(100, n), n,
      record.wall_s, n);
  std::printf("memory: %.0f MB at keyframe %zu, %.0f MB at the end\n",
              rss_mb[std::min<std::size_t>(199, n - 1)], std::min<std::size_t>(200, n),
              rss_mb.back());
  std::printf("per keyframe in %s\n", o.out.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!geofusion::readCommandLine("soak_benchmark", usage, [&] { parse(argc, argv, &o); }))
    return 2;
  GeoFusionConfig config;
  if (!o.config.apply("soak_benchmark", &config)) return 2;
  std::ofstream csv(o.out);
  if (!csv) {
    std::cerr << "soak_benchmark: cannot write " << o.out << "\n";
    return 1;
  }

  ModelSet models;
  const bool ycb = loadModels(o, config, &models);
  SuiteSpec suite;
  suiteByName("bench", &suite);
  if (!DetectorModel::byName(o.detector, &suite.detector)) {
    std::cerr << "soak_benchmark: unknown --detector " << o.detector << "\n";
    return 2;
  }
  scalePersistentErrors(&suite.detector.persistence, o.bias_scale);
  std::vector<ClutterScene> scenes;
  if (!makeScenes(o, suite, models, &scenes)) return 1;
  const std::vector<RunFrame> run = makeRun(o, suite, scenes);
  const PinholeIntrinsics K;
  std::vector<std::unique_ptr<SequenceRenderer>> renderers;
  for (const auto& scene : scenes)
    renderers.push_back(std::make_unique<SequenceRenderer>(scene, K));
  std::printf(
      "soak: %zu keyframes, %d tables of %d %s objects, visits of %d keyframes in turn; method %s\n"
      "detector: %s, persistent errors x %.2f\nconfiguration: %s\n",
      run.size(), o.tables, o.objects, ycb ? "YCB-Video" : "primitive", o.visit,
      toString(config.estimator.method), o.detector.c_str(), o.bias_scale,
      configDiff(config).c_str());

  SoakRecord record;
  const KeyframeResult final =
      runKeyframes(o, config, suite, models, run, renderers, K, &csv, &record);
  printMapScores(o, scenes, run, final, record.relocalisations);
  printTimes(o, record);
  return 0;
}
