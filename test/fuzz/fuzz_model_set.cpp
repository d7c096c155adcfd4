#include "fuzz_targets.h"

#include "geofusion/model/object_model.h"

#include <cmath>
#include <string>
#include <vector>

namespace geofusion {
namespace fuzz {

namespace {
// The files a model set may name beside it: a tetrahedron and some of its points.
const char kBoxObj[] =
    "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\n"
    "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
const char kBoxXyz[] = "0 0 0\n0.1 0 0\n0 0.1 0\n0 0 0.1\n0.02 0.02 0.02\n";
}  // namespace

int fuzzModelSet(const std::uint8_t* data, std::size_t size) {
  static const bool files = [] {
    writeScratchFile("box.obj", reinterpret_cast<const std::uint8_t*>(kBoxObj),
                     sizeof(kBoxObj) - 1);
    writeScratchFile("box.xyz", reinterpret_cast<const std::uint8_t*>(kBoxXyz),
                     sizeof(kBoxXyz) - 1);
    return true;
  }();
  (void)files;
  const std::string path = writeScratchFile("model_set.yaml", data, size);
  ModelSet models;
  std::vector<std::string> errors;
  if (!loadModelSet(path, "", "", &models, &errors)) {
    FUZZ_CHECK(!errors.empty());
    return 0;
  }
  FUZZ_CHECK(models.size() > 0);
  for (const auto& model : models.models()) {
    FUZZ_CHECK(models.find(model->name) == model.get());
    FUZZ_CHECK(!model->mesh.empty());
    const int vertices = static_cast<int>(model->mesh.vertices.size());
    for (const Eigen::Vector3i& t : model->mesh.triangles)
      FUZZ_CHECK(t.minCoeff() >= 0 && t.maxCoeff() < vertices);
    FUZZ_CHECK(!model->points.empty());
  }
  return 0;
}

}  // namespace fuzz
}  // namespace geofusion

#ifdef GEOFUSION_LIBFUZZER
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return geofusion::fuzz::fuzzModelSet(data, size);
}
#endif
