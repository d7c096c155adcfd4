// Writes a map for simulators: the final map of a results file (run_offline's, or a map saved by
// the node's ~save_map or its autosave) as an SDF world and a URDF with their meshes
// (docs/scene_export.md). The objects as the stability check puts them: each object's convex
// collision shapes, mass density x volume, the support plane as a static box, gravity along the
// configuration's estimator.gravity, friction and density from its physics section.
//
//   export_scene --results RESULTS.yaml --out FOLDER [--model-set primitives|ycb_video|FILE.yaml]
//       [--models DIR] [--params FILE] [--set KEY=VALUE]... [--check]
//
// --check: also runs the stability check on the map and prints each object's motion.
// The model set defaults to the one the results file names. Exit code 0; 1 when the results,
// models or folder cannot be read or written; 2 for bad arguments. Objects that cannot be
// exported are named on stderr and the rest is written.
#include "command_line.h"
#include "config_option.h"
#include "geofusion/estimation/map_stability.h"
#include "geofusion/estimation/run_results.h"
#include "model_set_option.h"

#include <cstdio>
#include <iostream>
#include <string>

namespace {

struct Options {
  std::string results, out, model_set, models_dir;
  geofusion::ConfigOptions config;
  bool check = false;
};

void usage() {
  std::cerr << "usage: export_scene --results RESULTS.yaml --out FOLDER\n"
               "         [--model-set primitives|ycb_video|FILE.yaml] [--models DIR]\n"
               "         [--params FILE] [--set KEY=VALUE]... [--check]\n";
}

Options parse(int argc, char** argv) {
  Options o;
  geofusion::CommandLine args;
  args.value("--results", &o.results);
  args.value("--out", &o.out);
  args.value("--model-set", &o.model_set);
  args.value("--models", &o.models_dir);
  args.toggle("--check", &o.check);
  o.config.declare(&args);
  args.parse(argc, argv, usage);
  if (o.results.empty() || o.out.empty())
    throw std::runtime_error("--results and --out are required");
  return o;
}

void printCheck(const geofusion::physics::StabilityResult& s) {
  std::printf("stability: %d of %d checked objects stable (%d start interpenetrating)\n", s.stable,
              s.checked, s.interpenetrating);
  for (const auto& m : s.bodies)
    std::printf("  object %d: %s, moved %.1f mm, turned %.1f deg%s\n", m.id,
                !m.simulated ? "not simulated"
                : m.stable   ? "stable"
                             : "unstable",
                1000 * m.translation_m, m.rotation_deg,
                m.interpenetrating ? " (starts interpenetrating)" : "");
}

}  // namespace

int main(int argc, char** argv) {
  using namespace geofusion;
  Options opt;
  if (!readCommandLine("export_scene", usage, [&] { opt = parse(argc, argv); })) return 2;
  GeoFusionConfig config;
  if (!opt.config.apply("export_scene", &config)) return 2;
  const std::string set = opt.model_set.empty() ? modelSetOf(opt.results) : opt.model_set;
  ModelSet models;
  if (!loadModelSetOption("export_scene", set, opt.models_dir, &models)) return 1;
  RunResults results;
  std::string error;
  if (!readRunResults(opt.results, models, &results, &error)) {
    std::cerr << "export_scene: " << error << "\n";
    return 1;
  }
  physics::SceneExport exported;
  const auto& objects = results.final_map.objects;
  if (!exportMapScene(objects, &results.support_plane, config.estimator.gravity,
                      config.estimator.physics, opt.out, &exported, &error)) {
    std::cerr << "export_scene: " << error << "\n";
    return 1;
  }
  for (const std::string& w : exported.warnings)
    std::cerr << "export_scene: warning: " << w << "\n";
  std::printf("exported %d of %zu objects: %s, %s, %zu meshes\n", exported.exported, objects.size(),
              exported.sdf_path.c_str(), exported.urdf_path.c_str(), exported.mesh_paths.size());
  if (opt.check)
    printCheck(checkMapStability(objects, &results.support_plane, config.estimator.gravity,
                                 config.estimator.physics));
  return 0;
}
