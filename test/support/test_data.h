// Where tests find the YCB-Video models: $GEOFUSION_YCB_DIR, else ../shared/data/ycb_video
// beside the repository. They are licensed data and never copied into the repository.
#pragma once

#include "geofusion/model/object_model.h"

#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

namespace geofusion {
namespace test {

inline std::string ycbDir() {
  if (const char* env = std::getenv("GEOFUSION_YCB_DIR")) return env;
  return std::string(GEOFUSION_SOURCE_DIR) + "/../shared/data/ycb_video";
}

/// True when any of the messages contains `what`.
inline bool anyMentions(const std::vector<std::string>& messages, const std::string& what) {
  for (const auto& m : messages) {
    if (m.find(what) != std::string::npos) return true;
  }
  return false;
}

inline bool haveYcb() {
  return std::ifstream(ycbDir() + "/classes.txt").good();
}

/// Loads the YCB-Video model set (config/models/ycb_video.yaml) from ycbDir().
inline bool loadYcbModels(ModelSet* models, std::vector<std::string>* errors) {
  return ModelSet::load(std::string(GEOFUSION_SOURCE_DIR) + "/config/models/ycb_video.yaml",
                        ycbDir(), models, errors);
}

}  // namespace test
}  // namespace geofusion
