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

int main(int argc, char** argv) {
  std::string models_dir;
  bool models_given = false;
  int rounds = 40, stride = 1;
  bool full_frame = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--models" && i + 1 < argc)
      models_dir = argv[++i], models_given = true;
    else if (a == "--rounds" && i + 1 < argc)
      rounds = std::max(1, std::atoi(argv[++i]));
    else if (a == "--stride" && i + 1 < argc)
      stride = std::max(1, std::atoi(argv[++i]));
    else if (a == "--full-frame")
      full_frame = true;
    else {
      std::fprintf(stderr, "usage: %s [--models DIR] [--rounds N] [--stride N] [--full-frame]\n",
                   argv[0]);
      return 2;
    }
  }

  if (!models_given) models_dir = defaultYcbDir("consistency_benchmark");
  ModelSet models;
  std::vector<std::string> errors;
  const std::string yaml =
      requirePackageDir("consistency_benchmark") + "/config/models/ycb_video.yaml";
  if (!std::ifstream(models_dir + "/classes.txt").good() ||
      !ModelSet::load(yaml, models_dir, &models, &errors) || models.size() == 0) {
    if (models_given) {  // never other data than the user named
      std::fprintf(stderr, "consistency_benchmark: cannot load the YCB-Video models of %s\n",
                   models_dir.c_str());
      for (const auto& e : errors) std::fprintf(stderr, "  %s\n", e.c_str());
      return 1;
    }
    std::printf("YCB-Video models not found at %s: using the built-in primitives\n",
                models_dir.c_str());
    models = ModelSet::builtinPrimitives();
  }
  for (const auto& e : errors) std::printf("model error: %s\n", e.c_str());

  auto renderer = std::make_shared<OffscreenRenderer>();
  if (!renderer->ok()) {
    std::fprintf(stderr, "%s\n", renderer->error().c_str());
    return 1;
  }
  const PinholeIntrinsics K;
  // 25 objects on a 5 x 5 grid on a table, seen from 0.8 m above its near edge.
  const Eigen::Isometry3d T_world_cam =
      lookAt(Eigen::Vector3d(0.0, -0.75, 0.55), Eigen::Vector3d(0.0, 0.0, 0.0));
  const Eigen::Isometry3d T_cam_world = T_world_cam.inverse();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> yaw(-M_PI, M_PI);
  std::vector<std::shared_ptr<const ObjectModel>> objects;
  std::vector<Eigen::Isometry3d> T_cam_obj;
  std::vector<RenderItem> items;
  RenderItem table;
  table.mesh = renderer->addMesh(makeBox(Eigen::Vector3d(1.2, 0.9, 0.04)));
  table.T_cam_model = T_cam_world * Eigen::Translation3d(0.0, 0.1, -0.02);
  items.push_back(table);
  std::size_t triangles = 0;
  for (int i = 0; i < 25; ++i) {
    const auto& m = models.models()[static_cast<std::size_t>(i) % models.size()];
    Eigen::Vector3f lo, hi;
    m->mesh.bounds(&lo, &hi);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(yaw(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(-0.36 + 0.18 * (i % 5), -0.2 + 0.14 * (i / 5), -lo.z());
    objects.push_back(m);
    T_cam_obj.push_back(T_cam_world * T);
    RenderItem it;
    it.mesh = renderer->addMesh(m->mesh);
    it.T_cam_model = T_cam_obj.back();
    it.instance_id = static_cast<std::uint16_t>(i + 1);
    items.push_back(it);
    triangles += m->mesh.triangles.size();
  }
  RenderedImages observed;
  if (!renderer->render(K, items, &observed, PixelBox{}, OffscreenRenderer::kDepth)) {
    std::fprintf(stderr, "%s\n", renderer->error().c_str());
    return 1;
  }
  const DepthImageView depth{observed.depth.data(), K.width, K.height};

  ConsistencyConfig config;
  config.pixel_stride = stride;
  ConsistencyScorer scorer(renderer, config);
  // Detections: the true poses with detector-like noise (1 cm, 3 degrees).
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> ms;
  double sum_score = 0.0;
  long pixels = 0;
  RenderedImages full;
  for (int r = 0; r < rounds + 1; ++r) {  // round 0 warms up (mesh upload, JIT)
    for (std::size_t i = 0; i < objects.size(); ++i) {
      Eigen::Isometry3d T = T_cam_obj[i];
      T.translation() += 0.01 * Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      T.linear() = Eigen::AngleAxisd(0.05 * noise(rng), Eigen::Vector3d::UnitX()) * T.linear();
      const auto t0 = std::chrono::steady_clock::now();
      ConsistencyResult res;
      if (full_frame) {
        RenderItem it;
        it.mesh = items[i + 1].mesh;  // the full mesh
        it.T_cam_model = T;
        renderer->render(K, {it}, &full, PixelBox{}, OffscreenRenderer::kDepth);
        res = compareDepth(full, depth, K, config);
      } else {
        res = scorer.score(objects[i], T, depth, K);
      }
      const auto t1 = std::chrono::steady_clock::now();
      if (r == 0) continue;
      ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      sum_score += res.score;
      pixels += res.rendered;
    }
  }
  std::size_t render_triangles = 0, one_sided = 0;
  for (const auto& m : objects) {
    const TriangleMesh simplified =
        simplifyMesh(m->mesh, static_cast<std::size_t>(config.render_mesh_triangles),
                     config.render_mesh_max_error_m);
    render_triangles += simplified.triangles.size();
    one_sided += checkWatertight(simplified).closedOutward();  // drawn without back faces
  }
  // How the score falls with pose error: mean over the 25 objects and 8 random directions.
  std::vector<std::pair<double, double>> curve;
  for (double cm : {0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 5.0}) {
    double sum = 0.0;
    int n = 0;
    for (std::size_t i = 0; i < objects.size(); ++i) {
      for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3d dir =
            Eigen::Vector3d(noise(rng), noise(rng), noise(rng)).normalized();
        Eigen::Isometry3d T = T_cam_obj[i];
        T.translation() += 0.01 * cm * dir;
        sum += scorer.score(objects[i], T, depth, K).score;
        ++n;
      }
    }
    curve.emplace_back(cm, sum / n);
  }
  // Depth refinement, scoring included: detections 3 cm off along the ray and turned 3 degrees,
  // as a colour-only estimator's.
  DepthRefiner refiner(&scorer, DepthRefinementConfig());
  std::vector<double> refine_ms, refine_error_mm;
  int accepted = 0;
  for (int r = 0; r < rounds; ++r) {
    for (std::size_t i = 0; i < objects.size(); ++i) {
      Eigen::Isometry3d T = T_cam_obj[i];
      T.translation() += 0.03 * T.translation().normalized();
      T.linear() = Eigen::AngleAxisd(0.05 * noise(rng), Eigen::Vector3d::UnitX()) * T.linear();
      const auto t0 = std::chrono::steady_clock::now();
      const DepthRefinement res = refiner.refine(objects[i], T, depth, K);
      refine_ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      accepted += res.accepted();
      if (res.accepted())
        refine_error_mm.push_back(
            1000 * (res.T_cam_obj.translation() - T_cam_obj[i].translation()).norm());
    }
  }
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const double total_s = std::accumulate(ms.begin(), ms.end(), 0.0) / 1000.0;
  std::printf("consistency score speed (%s, %s, stride %d, LP_NUM_THREADS=%s)\n",
              models.name().c_str(), full_frame ? "full-frame render" : "region render", stride,
              std::getenv("LP_NUM_THREADS") ? std::getenv("LP_NUM_THREADS") : "unset");
  std::printf("  detections a round      %zu, rounds %d\n", objects.size(), rounds);
  std::printf("  triangles               %zu in the meshes, %zu rendered for scoring\n", triangles,
              full_frame ? triangles : render_triangles);
  std::printf("  meshes drawn one-sided  %zu of %zu (closed, wound outward: back faces skipped)\n",
              one_sided, objects.size());
  std::printf("  rendered points a score %.0f (mean)\n", static_cast<double>(pixels) / ms.size());
  std::printf("  mean score (1 cm, 3 deg) %.3f\n", sum_score / ms.size());
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
      percentile(refine_ms, 0.5), percentile(refine_ms, 0.95));
  std::printf("  refinements accepted    %d of %zu; translation error after %.1f mm median\n",
              accepted, refine_ms.size(),
              refine_error_mm.empty() ? 0.0 : percentile(refine_error_mm, 0.5));
  std::printf("  peak memory             %.1f MB (max resident set)\n", usage.ru_maxrss / 1024.0);
  return 0;
}
