// make_model_set: a folder of meshes -> a model-set YAML GeoFusion loads (docs/model_sets.md).
//
//   make_model_set --meshes DIR --out models.yaml [--name SET] [--previews DIR] [--first-id N]
//                  [--skip-bad] [--trials] [--quiet]
//
// DIR holds either mesh files (OBJ, PLY, STL, anything assimp reads; the class is the file's
// name without extension) or one folder per class with its mesh inside (the class is the folder's
// name; textured.obj is preferred, as in YCB-Video). Each mesh is checked and measured:
//   - units: a mesh larger than 2 m is read as millimetres and scaled by 0.001 (the YAML's
//     `scale:`), a mesh smaller than 5 mm is warned about;
//   - watertightness: edges used by one triangle (holes) or by three or more are counted and
//     warned about (depth rendering works anyway; the convex hull features too);
//   - symmetry: rotations about the model frame's axes and the principal axes found numerically
//     (model/model_import.h), continuous or discrete, written to the YAML;
//   - surface features: planes, cylinder sides and edges from the convex hull (as the estimator
//     computes them), written to the YAML; with --previews, a PNG per class showing them.
// Ids are given in the order of the classes' names from --first-id (default 1). Nothing is written
// when a mesh cannot be loaded, unless --skip-bad leaves it out. Exit 0 on success, 1 on any
// failure (with the reason), 2 on bad usage.
#include "command_line.h"
#include "geofusion/common/atomic_file.h"
#include "geofusion/model/model_import.h"
#include "geofusion/model/surface_features.h"
#include "geofusion/render/model_preview.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace geofusion;

namespace {

struct Options {
  std::string meshes, out, name, previews;
  int first_id = 1;
  bool skip_bad = false;
  bool quiet = false;
  bool trials = false;
};

void usage() {
  std::printf(
      "usage: make_model_set --meshes DIR --out models.yaml [--name SET] [--previews DIR]\n"
      "                      [--first-id N=1] [--skip-bad] [--quiet]\n"
      "  --meshes    mesh files (class = file name), or one folder per class with its mesh\n"
      "  --out       the model-set YAML to write (mesh paths relative to --meshes)\n"
      "  --name      the set's name (default: the folder's name)\n"
      "  --previews  write <class>.png per class: its features and symmetry axes drawn\n"
      "  --first-id  class ids from this number, in the order of the class names\n"
      "  --skip-bad  leave out meshes that do not load (default: write nothing)\n"
      "  --trials    print every rotation tried for the symmetry and how far it moved the\n"
      "              surface (quantile distance vs tolerance)\n");
}

bool isMesh(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  for (const char* known : {".obj", ".ply", ".stl", ".off", ".dae", ".fbx", ".gltf", ".glb"})
    if (ext == known) return true;
  return false;
}

// (class name, mesh path relative to the folder), sorted by name.
std::vector<std::pair<std::string, std::string>> findMeshes(const std::string& dir) {
  std::vector<std::pair<std::string, std::string>> found;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.is_regular_file() && isMesh(entry.path())) {
      found.emplace_back(entry.path().stem().string(), entry.path().filename().string());
    } else if (entry.is_directory()) {
      std::vector<fs::path> inside;
      for (const auto& f : fs::directory_iterator(entry.path()))
        if (f.is_regular_file() && isMesh(f.path())) inside.push_back(f.path());
      if (inside.empty()) continue;
      std::sort(inside.begin(), inside.end());
      const auto textured = std::find_if(inside.begin(), inside.end(), [](const fs::path& p) {
        return p.filename() == "textured.obj";
      });
      const fs::path mesh = textured != inside.end() ? *textured : inside.front();
      found.emplace_back(entry.path().filename().string(),
                         entry.path().filename().string() + "/" + mesh.filename().string());
    }
  }
  std::sort(found.begin(), found.end());
  return found;
}

std::string millimetres(const Eigen::Vector3f& v) {
  std::ostringstream s;
  s.precision(1);
  s << std::fixed << 1000 * v.x() << " x " << 1000 * v.y() << " x " << 1000 * v.z() << " mm";
  return s.str();
}

// One class measured: its entry for the YAML, and what the user should know about it.
bool measureClass(const Options& o, const std::string& name, const std::string& relative, int id,
                  ModelSetEntry* entry, std::vector<std::string>* warnings, std::string* error) {
  TriangleMesh mesh;
  if (!loadMesh(o.meshes + "/" + relative, &mesh, error)) return false;
  entry->name = name;
  entry->id = id;
  entry->mesh = relative;
  const UnitsCheck units = checkUnits(mesh);
  if (!units.message.empty()) warnings->push_back(units.message);
  entry->scale = units.scale;
  scaleMesh(units.scale, &mesh);
  const WatertightCheck closed = checkWatertight(mesh);
  if (!closed.watertight()) {
    warnings->push_back("not watertight: " + std::to_string(closed.boundary_edges) +
                        " hole edges, " + std::to_string(closed.non_manifold_edges) +
                        " edges shared by three or more triangles (of " +
                        std::to_string(closed.edges) + ")");
  }
  const SymmetryDetection symmetry = detectSymmetry(mesh);
  entry->symmetry = symmetry.symmetry;
  if (o.trials) {
    std::printf("  %s: colour mismatch without rotation %.3f\n", name.c_str(),
                symmetry.colour_baseline);
    for (const auto& t : symmetry.trials) {
      std::printf(
          "  %s: %7.2f deg about [%6.3f %6.3f %6.3f]: %6.2f mm (tolerance %.2f mm), colour "
          "mismatch %.3f%s\n",
          name.c_str(), t.angle_deg, t.axis.x(), t.axis.y(), t.axis.z(), 1000 * t.distance_m,
          1000 * t.tolerance_m, t.colour_mismatch, t.maps_onto_itself() ? " *" : "");
    }
  }
  if (symmetry.axis_offset_m > symmetry.tolerance_m) {
    std::ostringstream why;
    why.precision(1);
    why << std::fixed << "its symmetry axes pass " << 1000 * symmetry.axis_offset_m
        << " mm from the model origin (through the box centre [" << 1000 * symmetry.centre.x()
        << ", " << 1000 * symmetry.centre.y() << ", " << 1000 * symmetry.centre.z()
        << "] mm); GeoFusion applies symmetries about the origin: move the mesh's origin there "
           "(and the detector's object frame with it) for them to hold exactly";
    warnings->push_back(why.str());
  }
  entry->features = extractSurfaceFeatures(mesh);
  entry->notes = {name + ": " + millimetres(mesh.extents()) + ", " +
                  (closed.watertight() ? "watertight" : "not watertight") + "; symmetry " +
                  describe(entry->symmetry) + "; features " + describe(entry->features)};
  for (const auto& w : *warnings) entry->notes.push_back(name + ": " + w);
  if (!o.previews.empty()) {
    const std::vector<std::string> caption = {
        name + " (id " + std::to_string(id) + "), " + millimetres(mesh.extents()),
        "symmetry: " + describe(entry->symmetry), "features: " + describe(entry->features),
        "green: planes, yellow: normals, magenta: cylinder sides, red: edges, cyan: symmetry"};
    if (!writeModelPreview(mesh, entry->features, entry->symmetry, symmetry.centre, caption,
                           o.previews + "/" + name + ".png", error))
      return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  try {
    CommandLine args;
    args.value("--meshes", &o.meshes);
    args.value("--out", &o.out);
    args.value("--name", &o.name);
    args.value("--previews", &o.previews);
    args.value("--first-id", &o.first_id);
    args.toggle("--skip-bad", &o.skip_bad);
    args.toggle("--quiet", &o.quiet);
    args.toggle("--trials", &o.trials);
    args.parse(argc, argv, usage);
    if (o.meshes.empty() || o.out.empty()) throw std::runtime_error("--meshes and --out needed");
  } catch (const std::exception& e) {
    std::cerr << "make_model_set: " << e.what() << "\n";
    usage();
    return 2;
  }
  std::error_code ec;
  if (!fs::is_directory(o.meshes, ec)) {
    std::cerr << "make_model_set: " << o.meshes << " is not a folder\n";
    return 1;
  }
  if (!o.previews.empty() && !fs::create_directories(o.previews, ec) && ec) {
    std::cerr << "make_model_set: cannot make " << o.previews << ": " << ec.message() << "\n";
    return 1;
  }
  if (o.name.empty()) o.name = fs::path(o.meshes).lexically_normal().filename().string();
  if (o.name.empty()) o.name = fs::absolute(o.meshes).parent_path().filename().string();
  const auto meshes = findMeshes(o.meshes);
  if (meshes.empty()) {
    std::cerr << "make_model_set: no mesh (OBJ, PLY, STL, ...) in " << o.meshes << "\n";
    return 1;
  }
  std::vector<ModelSetEntry> entries;
  std::vector<std::string> failures;
  int id = o.first_id;
  for (const auto& [name, relative] : meshes) {
    ModelSetEntry entry;
    std::vector<std::string> warnings;
    std::string error;
    if (!measureClass(o, name, relative, id, &entry, &warnings, &error)) {
      failures.push_back(name + ": " + error);
      std::cerr << "make_model_set: " << name << ": " << error << "\n";
      continue;
    }
    ++id;
    for (const auto& w : warnings)
      std::cerr << "make_model_set: warning: " << name << ": " << w << "\n";
    if (!o.quiet) std::printf("%s\n", entry.notes.front().c_str());
    entries.push_back(std::move(entry));
  }
  if (!failures.empty() && !o.skip_bad) {
    std::cerr << "make_model_set: " << failures.size()
              << " mesh(es) could not be used; nothing written (--skip-bad leaves them out)\n";
    return 1;
  }
  if (entries.empty()) {
    std::cerr << "make_model_set: no usable mesh; nothing written\n";
    return 1;
  }
  std::string error;
  const std::string yaml = modelSetYaml(o.name, entries);
  if (!writeTextAtomically(o.out, yaml, &error)) {
    std::cerr << "make_model_set: " << error << "\n";
    return 1;
  }
  std::printf("make_model_set: %zu classes written to %s%s%s\n", entries.size(), o.out.c_str(),
              o.previews.empty() ? "" : ", previews in ", o.previews.c_str());
  return failures.empty() ? 0 : 1;
}
