// Helpers shared by the core's YAML writers (ground truth, run results). Private to the core.
#pragma once

#include <yaml-cpp/yaml.h>
#include "atomic_file.h"

#include <Eigen/Geometry>

#include <cstdio>
#include <fstream>
#include <string>

namespace geofusion {
namespace yaml_io {

/// `key: [x, y, z, qx, qy, qz, qw]` (flow sequence) of a pose.
inline void emitPose(YAML::Emitter& out, const char* key, const Eigen::Isometry3d& T) {
  const Eigen::Quaterniond q(T.linear());
  const Eigen::Vector3d& t = T.translation();
  out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq << t.x() << t.y() << t.z()
      << q.x() << q.y() << q.z() << q.w() << YAML::EndSeq;
}

/// Writes `header` then the emitter's document to `path` through a temporary file and a rename,
/// so that no reader ever sees half a file.
inline bool writeAtomically(const std::string& path, const std::string& header,
                            const YAML::Emitter& out, std::string* error) {
  if (!out.good()) {
    if (error) *error = "YAML emitter: " + out.GetLastError();
    return false;
  }
  return writeFileAtomically(
      path,
      [&](const std::string& tmp) {
        std::ofstream file(tmp);
        file << header << out.c_str() << "\n";
        return file.good();
      },
      error);
}

}  // namespace yaml_io
}  // namespace geofusion
