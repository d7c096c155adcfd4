#include "fuzz_targets.h"

#include "geofusion/config/config.h"

#include <string>

namespace geofusion {
namespace fuzz {

int fuzzConfig(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  GeoFusionConfig config;
  ConfigReport report;
  const bool ok = loadConfigText(text, "fuzz.yaml", &config, &report);
  FUZZ_CHECK(ok == report.ok());
  if (!ok) return 0;
  // What was loaded is a valid configuration: written out and read again it is the same.
  const std::string yaml = configYaml(config);
  GeoFusionConfig again;
  ConfigReport again_report;
  FUZZ_CHECK(loadConfigText(yaml, "configYaml", &again, &again_report));
  FUZZ_CHECK(again_report.warnings.empty());
  FUZZ_CHECK(configYaml(again) == yaml);
  FUZZ_CHECK(!configDiff(config).empty());
  return 0;
}

}  // namespace fuzz
}  // namespace geofusion

#ifdef GEOFUSION_LIBFUZZER
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return geofusion::fuzz::fuzzConfig(data, size);
}
#endif
