// Every seed (test/fuzz/corpus/<target>/) and every input a fuzzer once failed on
// (test/fuzz/regressions/<target>/) through the fuzz targets, built with the package's compiler:
// each must return 0 without crashing or tripping a FUZZ_CHECK (scripts/fuzz.sh runs the
// fuzzers themselves). GEOFUSION_FUZZ_DIR: test/fuzz.
#include "fuzz_targets.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace geofusion {
namespace fuzz {
namespace {

using Target = int (*)(const std::uint8_t*, std::size_t);

// The files of test/fuzz/<kind>/<target>/, sorted; none when the folder does not exist.
std::vector<std::string> inputs(const std::string& kind, const std::string& target) {
  std::vector<std::string> files;
  const std::filesystem::path dir = std::filesystem::path(GEOFUSION_FUZZ_DIR) / kind / target;
  if (!std::filesystem::is_directory(dir)) return files;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (entry.is_regular_file()) files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

// Runs the target on every seed (at least one) and regression input of its folders.
void runAll(const std::string& target, Target fn) {
  const std::vector<std::string> seeds = inputs("corpus", target);
  ASSERT_FALSE(seeds.empty()) << "no seed in " << GEOFUSION_FUZZ_DIR << "/corpus/" << target;
  std::vector<std::string> all = seeds;
  for (const std::string& f : inputs("regressions", target)) all.push_back(f);
  for (const std::string& path : all) {
    SCOPED_TRACE(path);
    std::ifstream in(path, std::ios::binary);
    ASSERT_TRUE(in.good());
    const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                          std::istreambuf_iterator<char>());
    const std::uint8_t none = 0;  // libFuzzer never passes a null pointer, even for no bytes
    EXPECT_EQ(0, fn(bytes.empty() ? &none : bytes.data(), bytes.size()));
  }
}

TEST(FuzzRegressions, Detections) {
  runAll("detections", fuzzDetections);
}
TEST(FuzzRegressions, ModelSet) {
  runAll("model_set", fuzzModelSet);
}
TEST(FuzzRegressions, VisionDetections) {
  runAll("vision_detections", fuzzVisionDetections);
}
TEST(FuzzRegressions, Config) {
  runAll("config", fuzzConfig);
}
TEST(FuzzRegressions, Mesh) {
  runAll("mesh", fuzzMesh);
}
TEST(FuzzRegressions, Bag) {
  runAll("bag", fuzzBag);
}

}  // namespace
}  // namespace fuzz
}  // namespace geofusion
