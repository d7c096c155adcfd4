// Fuzz targets (scripts/fuzz.sh, `make fuzz`): each takes arbitrary bytes, returns 0 and must
// never crash, leak, hang or trip a sanitizer on any of them; a broken invariant of the code under
// test aborts (FUZZ_CHECK). libFuzzer calls them through a thin LLVMFuzzerTestOneInput, compiled
// only for the fuzzers (GEOFUSION_LIBFUZZER); test_fuzz_regressions (gtest) runs the seed corpus
// (test/fuzz/corpus/<target>/) and the inputs that once failed (test/fuzz/regressions/<target>/)
// through the same functions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

/// Aborts with the failed condition: an invariant of the code under test does not hold.
#define FUZZ_CHECK(condition)                                                                 \
  do {                                                                                        \
    if (!(condition)) {                                                                       \
      std::fprintf(stderr, "%s:%d: FUZZ_CHECK failed: %s\n", __FILE__, __LINE__, #condition); \
      std::abort();                                                                           \
    }                                                                                         \
  } while (0)

namespace geofusion {
namespace fuzz {

/// The bytes as a serialised geofusion/DetectionArray, converted (fromMsg) and checked as the
/// estimator does (FrameByFrame with the built-in primitives' classes).
int fuzzDetections(const std::uint8_t* data, std::size_t size);
/// The bytes as a model-set YAML file (loadModelSet); its folder holds box.obj and box.xyz.
int fuzzModelSet(const std::uint8_t* data, std::size_t size);
/// The bytes as a parameter YAML (loadConfigText); a loaded configuration must survive its own
/// configYaml() unchanged.
int fuzzConfig(const std::uint8_t* data, std::size_t size);
/// The first byte picks the file type (OBJ, PLY, STL, OFF), the rest is the mesh file
/// (loadMesh), then what a model set does with a loaded mesh (ModelSet::add).
int fuzzMesh(const std::uint8_t* data, std::size_t size);
/// The bytes as a bag file read as run_offline reads one: rosbag::View over every message,
/// instantiating the input types and converting them.
int fuzzBag(const std::uint8_t* data, std::size_t size);
/// The bytes as a serialised vision_msgs/Detection3DArray (the hand-written reader of
/// vision_detections.h): decoded, re-encoded and decoded the same, converted with the
/// primitives' class ids, every detection used or counted dropped.
int fuzzVisionDetections(const std::uint8_t* data, std::size_t size);

/// Writes the bytes to `name` in this process's scratch folder (made on first use, removed at
/// exit) and returns the file's path.
std::string writeScratchFile(const std::string& name, const std::uint8_t* data, std::size_t size);

}  // namespace fuzz
}  // namespace geofusion
