#include "fuzz_targets.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <system_error>

namespace geofusion {
namespace fuzz {

namespace {
// The scratch folder, made on first use and removed with the process's static objects.
struct Scratch {
  std::string dir;
  Scratch() {
    const char* tmp = std::getenv("TMPDIR");
    dir = std::string(tmp && *tmp ? tmp : "/tmp") + "/geofusion_fuzz_XXXXXX";
    if (!mkdtemp(dir.data())) throw std::runtime_error("cannot make " + dir);
  }
  ~Scratch() {
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
  }
};

const std::string& scratchDir() {
  static const Scratch scratch;
  return scratch.dir;
}
}  // namespace

std::string writeScratchFile(const std::string& name, const std::uint8_t* data, std::size_t size) {
  const std::string path = scratchDir() + "/" + name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path);
  return path;
}

}  // namespace fuzz
}  // namespace geofusion

#ifdef GEOFUSION_LIBFUZZER
// The fuzzers' sanitizer defaults (the environment's ASAN_OPTIONS still wins). Inputs are small
// (-max_len), so an allocation of more than 512 MB is a size read from the input and trusted: it
// is reported (allocation-size-too-big) rather than tried.
extern "C" const char* __asan_default_options() {
  return "max_allocation_size_mb=512";
}
#endif
