#include "fuzz_targets.h"

#include "geofusion/model/mesh.h"
#include "geofusion/model/object_model.h"

#include <string>

namespace geofusion {
namespace fuzz {

int fuzzMesh(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  // The file name's extension decides which of assimp's importers reads it.
  static const char* const kTypes[] = {"obj", "ply", "stl", "off"};
  const std::string path =
      writeScratchFile(std::string("mesh.") + kTypes[data[0] % 4], data + 1, size - 1);
  TriangleMesh mesh;
  std::string error;
  if (!loadMesh(path, &mesh, &error)) {
    FUZZ_CHECK(!error.empty());
    return 0;
  }
  FUZZ_CHECK(!mesh.empty());
  FUZZ_CHECK(mesh.uvs.empty() || mesh.uvs.size() == mesh.vertices.size());
  const int vertices = static_cast<int>(mesh.vertices.size());
  for (const Eigen::Vector3f& v : mesh.vertices) FUZZ_CHECK(v.allFinite());
  for (const Eigen::Vector3i& t : mesh.triangles)
    FUZZ_CHECK(t.minCoeff() >= 0 && t.maxCoeff() < vertices);
  // What a model set does with a mesh it loaded: evaluation points, surface features, hull.
  ModelSet models;
  ObjectModel model;
  model.name = "fuzz";
  model.id = 1;
  model.mesh = std::move(mesh);
  models.add(std::move(model));
  FUZZ_CHECK(models.size() == 1);
  return 0;
}

}  // namespace fuzz
}  // namespace geofusion

#ifdef GEOFUSION_LIBFUZZER
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return geofusion::fuzz::fuzzMesh(data, size);
}
#endif
