// The tools' --model-set / --models options: "ycb_video" names the package's YCB-Video model set
// (config/models/ycb_video.yaml) whose meshes come from --models, else $GEOFUSION_YCB_DIR, else
// ../shared/data/ycb_video beside the package's (real) folder: in a source checkout that is the
// shared data, in an install space it is absent and the folder has to be given. The package is
// found through ROS (ros::package), never through a path compiled in.
#pragma once

#include "geofusion/model/object_model.h"
#include "geofusion/ros/node_config.h"

#include <climits>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

namespace geofusion {

/// The package's folder, for a tool that reads the package's files (the model-set table): found
/// through ROS; without a sourced workspace the tool stops here, saying so, rather than reading
/// a path built from nothing and going on with other data than the user named.
inline std::string requirePackageDir(const std::string& tool) {
  const std::string dir = packageDir();
  if (dir.empty()) {
    std::cerr << tool
              << ": the geofusion package is not found (ROS_PACKAGE_PATH): source the "
                 "workspace's setup.bash first (e.g. source ~/.cache/geofusion/ws-*/devel/"
                 "setup.bash)\n";
    std::exit(1);
  }
  return dir;
}

/// The default YCB-Video models folder.
inline std::string defaultYcbDir(const std::string& tool = "geofusion") {
  const char* env = std::getenv("GEOFUSION_YCB_DIR");
  if (env) return env;
  char real[PATH_MAX];
  const std::string package = requirePackageDir(tool);
  return std::string(realpath(package.c_str(), real) ? real : package.c_str()) +
         "/../shared/data/ycb_video";
}

/// Loads the model set of a --model-set value (a name of the model-set table or a YAML file),
/// saying what went wrong on stderr under the tool's name. The tools find the YCB-Video meshes
/// beside the source tree when neither --models nor $GEOFUSION_YCB_DIR says where.
inline bool loadModelSetOption(const std::string& tool, const std::string& spec, std::string dir,
                               ModelSet* models, const SurfaceFeatureConfig& features = {}) {
  if (spec == "ycb_video" && dir.empty()) dir = defaultYcbDir(tool);
  std::vector<std::string> errors;
  const std::string package = spec == "primitives" ? "" : requirePackageDir(tool);
  if (!loadModelSet(spec, dir, package, models, &errors, features)) {
    std::cerr << tool << ": cannot load the model set " << spec << "\n";
    for (const auto& e : errors) std::cerr << "  " << e << "\n";
    return false;
  }
  for (const auto& e : errors) std::cerr << tool << ": warning: " << e << "\n";
  return true;
}

// The model set a ground-truth file names, from its header line (the file is read again with
// the models for its classes).
inline std::string modelSetOf(const std::string& gt_path) {
  std::FILE* f = std::fopen(gt_path.c_str(), "r");
  if (!f) return "primitives";
  char line[512];
  std::string set = "primitives";
  while (std::fgets(line, sizeof(line), f)) {
    const std::string s(line);
    if (s.rfind("model_set:", 0) == 0) {
      set = s.substr(10);
      set.erase(0, set.find_first_not_of(" \"'"));
      set.erase(set.find_last_not_of(" \"'\r\n") + 1);
      break;
    }
  }
  std::fclose(f);
  return set;
}

}  // namespace geofusion
