// Helpers shared by the YAML writers and readers of the modules (ground truth, run results):
// include from .cpp files only (it brings yaml-cpp).
#pragma once

#include <yaml-cpp/yaml.h>
#include "geofusion/common/atomic_file.h"
#include "geofusion/common/pose_validation.h"

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
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

/// The vector of `[x, y, z]` (yaml-cpp throws on a missing or non-numeric entry).
inline Eigen::Vector3d parseVector3(const YAML::Node& n) {
  return {n[0].as<double>(), n[1].as<double>(), n[2].as<double>()};
}

/// The pose of `[x, y, z, qx, qy, qz, qw]`; throws std::runtime_error naming `what` when the node
/// is not such a list, the quaternion is not unit or a value is not finite.
inline Eigen::Isometry3d parsePose(const YAML::Node& n, const char* what) {
  if (!n || !n.IsSequence() || n.size() != 7) {
    throw std::runtime_error(std::string(what) + ": expected [x, y, z, qx, qy, qz, qw]");
  }
  Eigen::Quaterniond q(n[6].as<double>(), n[3].as<double>(), n[4].as<double>(), n[5].as<double>());
  if (!(std::abs(q.norm() - 1.0) <= kUnitQuaternionTolerance)) {
    throw std::runtime_error(std::string(what) + ": quaternion is not unit");
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(n[0].as<double>(), n[1].as<double>(), n[2].as<double>());
  if (!T.matrix().allFinite()) throw std::runtime_error(std::string(what) + ": not finite");
  return T;
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
