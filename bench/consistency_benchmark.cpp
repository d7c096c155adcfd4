// Speed of the geometric consistency score: 25 detections of YCB-Video models scored against one
// 640x480 depth image, many rounds; prints median and p95 milliseconds a score, renders a second
// and peak memory; then the cost of one depth refinement (estimation/depth_refinement.h, scoring
// included) on detections 3 cm off along the ray. A benchmark that prints figures, not a test.
//
//   consistency_benchmark [--models DIR] [--rounds N] [--full-frame] [--stride N]
//
// DIR holds the YCB-Video models (default: ../shared/data/ycb_video beside the source tree);
// without it the built-in primitive models are used and the output says so. The renderer
// rasterises in the calling thread (one core) unless LP_NUM_THREADS says otherwise.
#include "geofusion/common/statistics.h"
#include "geofusion/estimation/depth_refinement.h"
#include "geofusion/model/model_import.h"
#include "geofusion/model/object_model.h"
#include "geofusion/render/consistency.h"
#include "model_set_option.h"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <numeric>
#include <random>
#include <string>
#include <vector>

using namespace geofusion;

namespace {

struct Options {
  std::string models_dir;
  bool models_given = false;
  int rounds = 40, stride = 1;
  bool full_frame = false;
};

// False, the usage printed, on an option it does not know.
bool parse(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--models" && i + 1 < argc)
      o->models_dir = argv[++i], o->models_given = true;
    else if (a == "--rounds" && i + 1 < argc)
      o->rounds = std::max(1, std::atoi(argv[++i]));
    else if (a == "--stride" && i + 1 < argc)
      o->stride = std::max(1, std::atoi(argv[++i]));
    else if (a == "--full-frame")
      o->full_frame = true;
    else {
      std::fprintf(stderr, "usage: %s [--models DIR] [--rounds N] [--stride N] [--full-frame]\n",
                   argv[0]);
      return false;
    }
  }
  return true;
}

// The YCB-Video models of o.models_dir; when that was not named and has none, the built-in
// primitives (and the output says so). False, having said why, when the named one cannot be
// loaded.
bool loadModels(const Options& o, ModelSet* models) {
  std::vector<std::string> errors;
  const std::string yaml =
      requirePackageDir("consistency_benchmark") + "/config/models/ycb_video.yaml";
  if (!std::ifstream(o.models_dir + "/classes.txt").good() ||
      !ModelSet::load(yaml, o.models_dir, models, &errors) || models->size() == 0) {
    if (o.models_given) {  // never other data than the user named
      std::fprintf(stderr, "consistency_benchmark: cannot load the YCB-Video models of %s\n",
                   o.models_dir.c_str());
      for (const auto& e : errors) std::fprintf(stderr, "  %s\n", e.c_str());
      return false;
    }
    std::printf("YCB-Video models not found at %s: using the built-in primitives\n",
                o.models_dir.c_str());
    *models = ModelSet::builtinPrimitives();
  }
  for (const auto& e : errors) std::printf("model error: %s\n", e.c_str());
  return true;
}

/// The benchmark's random numbers: one generator and one normal distribution, drawn from step
/// after step.
struct Random {
  std::mt19937 rng{3};
  std::normal_distribution<double> noise{0.0, 1.0};
};

/// The benchmark's scene and the depth image of it.
struct Table {
  std::vector<std::shared_ptr<const ObjectModel>> objects;
  std::vector<Eigen::Isometry3d> T_cam_obj;
  std::vector<RenderItem> items;  ///< the table, then the objects
  std::size_t triangles = 0;      ///< in the objects' meshes
  RenderedImages observed;
};

// 25 objects on a 5 x 5 grid on a table, seen from 0.8 m above its near edge, and their depth
// image. False, having said why, when it cannot be rendered.
bool makeTable(const ModelSet& models, const PinholeIntrinsics& K, OffscreenRenderer* renderer,
               Random* random, Table* table) {
  std::mt19937& rng = random->rng;
  const Eigen::Isometry3d T_world_cam =
      lookAt(Eigen::Vector3d(0.0, -0.75, 0.55), Eigen::Vector3d(0.0, 0.0, 0.0));
  const Eigen::Isometry3d T_cam_world = T_world_cam.inverse();
  std::uniform_real_distribution<double> yaw(-M_PI, M_PI);
  RenderItem top;
  top.mesh = renderer->addMesh(makeBox(Eigen::Vector3d(1.2, 0.9, 0.04)));
  top.T_cam_model = T_cam_world * Eigen::Translation3d(0.0, 0.1, -0.02);
  table->items.push_back(top);
  for (int i = 0; i < 25; ++i) {
    const auto& m = models.models()[static_cast<std::size_t>(i) % models.size()];
    Eigen::Vector3f lo, hi;
    m->mesh.bounds(&lo, &hi);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(yaw(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(-0.36 + 0.18 * (i % 5), -0.2 + 0.14 * (i / 5), -lo.z());
    table->objects.push_back(m);
    table->T_cam_obj.push_back(T_cam_world * T);
    RenderItem it;
    it.mesh = renderer->addMesh(m->mesh);
    it.T_cam_model = table->T_cam_obj.back();
    it.instance_id = static_cast<std::uint16_t>(i + 1);
    table->items.push_back(it);
    table->triangles += m->mesh.triangles.size();
  }
  if (!renderer->render(K, table->items, &table->observed, PixelBox{}, OffscreenRenderer::kDepth)) {
    std::fprintf(stderr, "%s\n", renderer->error().c_str());
    return false;
  }
  return true;
}

/// The scoring rounds: milliseconds a score, and what was scored.
struct ScoreRun {
  std::vector<double> ms;
  double sum_score = 0.0;
  long pixels = 0;
};

// Detections: the true poses with detector-like noise (1 cm, 3 degrees), each scored (rendered
// and compared) o.rounds times.
ScoreRun timeScores(const Options& o, const Table& table, const DepthImageView& depth,
                    const PinholeIntrinsics& K, const ConsistencyConfig& config,
                    OffscreenRenderer* renderer, ConsistencyScorer* scorer, Random* random) {
  std::mt19937& rng = random->rng;
  std::normal_distribution<double>& noise = random->noise;
  ScoreRun run;
  RenderedImages full;
  for (int r = 0; r < o.rounds + 1; ++r) {  // round 0 warms up (mesh upload, JIT)
    for (std::size_t i = 0; i < table.objects.size(); ++i) {
      Eigen::Isometry3d T = table.T_cam_obj[i];
      T.translation() += 0.01 * Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      T.linear() = Eigen::AngleAxisd(0.05 * noise(rng), Eigen::Vector3d::UnitX()) * T.linear();
      const auto t0 = std::chrono::steady_clock::now();
      ConsistencyResult res;
      if (o.full_frame) {
        RenderItem it;
        it.mesh = table.items[i + 1].mesh;  // the full mesh
        it.T_cam_model = T;
        renderer->render(K, {it}, &full, PixelBox{}, OffscreenRenderer::kDepth);
        res = compareDepth(full, depth, K, config);
      } else {
        res = scorer->score(table.objects[i], T, depth, K);
      }
      const auto t1 = std::chrono::steady_clock::now();
      if (r == 0) continue;
      run.ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      run.sum_score += res.score;
      run.pixels += res.rendered;
    }
  }
  return run;
}

/// The objects' meshes as the scorer draws them.
struct MeshCounts {
  std::size_t render_triangles = 0;  ///< after simplification
  std::size_t one_sided = 0;         ///< closed, wound outward: back faces skipped
};

MeshCounts countRenderedMeshes(const std::vector<std::shared_ptr<const ObjectModel>>& objects,
                               const ConsistencyConfig& config) {
  MeshCounts n;
  for (const auto& m : objects) {
    const TriangleMesh simplified =
        simplifyMesh(m->mesh, static_cast<std::size_t>(config.render_mesh_triangles),
                     config.render_mesh_max_error_m);
    n.render_triangles += simplified.triangles.size();
    n.one_sided += checkWatertight(simplified).closedOutward();  // drawn without back faces
  }
  return n;
}

// How the score falls with pose error: mean over the 25 objects and 8 random directions, by
// translation error (cm).
std::vector<std::pair<double, double>> scoreCurve(const Table& table, const DepthImageView& depth,
                                                  const PinholeIntrinsics& K,
                                                  ConsistencyScorer* scorer, Random* random) {
  std::mt19937& rng = random->rng;
  std::normal_distribution<double>& noise = random->noise;
  std::vector<std::pair<double, double>> curve;
  for (double cm : {0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 5.0}) {
    double sum = 0.0;
    int n = 0;
    for (std::size_t i = 0; i < table.objects.size(); ++i) {
      for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3d dir =
            Eigen::Vector3d(noise(rng), noise(rng), noise(rng)).normalized();
        Eigen::Isometry3d T = table.T_cam_obj[i];
        T.translation() += 0.01 * cm * dir;
        sum += scorer->score(table.objects[i], T, depth, K).score;
        ++n;
      }
    }
    curve.emplace_back(cm, sum / n);
  }
  return curve;
}

/// The depth refinements: milliseconds each, and the translation error of those accepted.
struct RefineRun {
  std::vector<double> ms, error_mm;
  int accepted = 0;
};

// Depth refinement, scoring included: detections 3 cm off along the ray and turned 3 degrees,
// as a colour-only estimator's.
RefineRun timeRefinements(const Options& o, const Table& table, const DepthImageView& depth,
                          const PinholeIntrinsics& K, ConsistencyScorer* scorer, Random* random) {
  std::mt19937& rng = random->rng;
  std::normal_distribution<double>& noise = random->noise;
  DepthRefiner refiner(scorer, DepthRefinementConfig());
  RefineRun run;
  for (int r = 0; r < o.rounds; ++r) {
    for (std::size_t i = 0; i < table.objects.size(); ++i) {
      Eigen::Isometry3d T = table.T_cam_obj[i];
      T.translation() += 0.03 * T.translation().normalized();
      T.linear() = Eigen::AngleAxisd(0.05 * noise(rng), Eigen::Vector3d::UnitX()) * T.linear();
      const auto t0 = std::chrono::steady_clock::now();
      const DepthRefinement res = refiner.refine(table.objects[i], T, depth, K);
      run.ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      run.accepted += res.accepted();
      if (res.accepted())
        run.error_mm.push_back(
            1000 * (res.T_cam_obj.translation() - table.T_cam_obj[i].translation()).norm());
    }
  }
  return run;
}

void printReport(const Options& o, const ModelSet& models, const Table& table,
                 const ScoreRun& scores, const MeshCounts& meshes,
                 const std::vector<std::pair<double, double>>& curve, const RefineRun& refinement) {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const std::vector<double>& ms = scores.ms;
  const double total_s = std::accumulate(ms.begin(), ms.end(), 0.0) / 1000.0;
  std::printf("consistency score speed (%s, %s, stride %d, LP_NUM_THREADS=%s)\n",
              models.name().c_str(), o.full_frame ? "full-frame render" : "region render", o.stride,
              std::getenv("LP_NUM_THREADS") ? std::getenv("LP_NUM_THREADS") : "unset");
  std::printf("  detections a round      %zu, rounds %d\n", table.objects.size(), o.rounds);
  std::printf("  triangles               %zu in the meshes, %zu rendered for scoring\n",
              table.triangles, o.full_frame ? table.triangles : meshes.render_triangles);
  std::printf("  meshes drawn one-sided  %zu of %zu (closed, wound outward: back faces skipped)\n",
              meshes.one_sided, table.objects.size());
  std::printf("  rendered points a score %.0f (mean)\n",
              static_cast<double>(scores.pixels) / ms.size());
  std::printf("  mean score (1 cm, 3 deg) %.3f\n", scores.sum_score / ms.size());
  std::printf("  ms a score              median %.3f  p95 %.3f  max %.3f\n", percentile(ms, 0.5),
              percentile(ms, 0.95), *std::max_element(ms.begin(), ms.end()));
  std::printf("  renders a second        %.0f\n", ms.size() / total_s);
  std::printf("  ms for 25 detections    %.2f (median x 25)\n", 25.0 * percentile(ms, 0.5));
  std::printf("  mean f_gc by translation error (cm):");
  for (const auto& c : curve) std::printf(" %.1f:%.2f", c.first, c.second);
  std::printf("\n");
  std::printf(
      "  ms a depth refinement   median %.3f  p95 %.3f (3 cm along the ray; scoring "
      "included)\n",
      percentile(refinement.ms, 0.5), percentile(refinement.ms, 0.95));
  std::printf("  refinements accepted    %d of %zu; translation error after %.1f mm median\n",
              refinement.accepted, refinement.ms.size(),
              refinement.error_mm.empty() ? 0.0 : percentile(refinement.error_mm, 0.5));
  std::printf("  peak memory             %.1f MB (max resident set)\n", usage.ru_maxrss / 1024.0);
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse(argc, argv, &o)) return 2;

  if (!o.models_given) o.models_dir = defaultYcbDir("consistency_benchmark");
  ModelSet models;
  if (!loadModels(o, &models)) return 1;

  auto renderer = std::make_shared<OffscreenRenderer>();
  if (!renderer->ok()) {
    std::fprintf(stderr, "%s\n", renderer->error().c_str());
    return 1;
  }
  const PinholeIntrinsics K;
  Random random;
  Table table;
  if (!makeTable(models, K, renderer.get(), &random, &table)) return 1;
  const DepthImageView depth{table.observed.depth.data(), K.width, K.height};

  ConsistencyConfig config;
  config.pixel_stride = o.stride;
  ConsistencyScorer scorer(renderer, config);
  const ScoreRun scores = timeScores(o, table, depth, K, config, renderer.get(), &scorer, &random);
  const MeshCounts meshes = countRenderedMeshes(table.objects, config);
  const std::vector<std::pair<double, double>> curve =
      scoreCurve(table, depth, K, &scorer, &random);
  const RefineRun refinement = timeRefinements(o, table, depth, K, &scorer, &random);
  printReport(o, models, table, scores, meshes, curve, refinement);
  return 0;
}
