// Helpers shared by the core's YAML writers (ground truth, run results). Private to the core.
#pragma once

#include <yaml-cpp/yaml.h>
#include "atomic_file.h"

#include "geofusion/core/contacts.h"

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

/// The pose of `[x, y, z, qx, qy, qz, qw]`; throws std::runtime_error naming `what` when the node
/// is not such a list, the quaternion is not unit or a value is not finite.
inline Eigen::Isometry3d parsePose(const YAML::Node& n, const char* what) {
  if (!n || !n.IsSequence() || n.size() != 7) {
    throw std::runtime_error(std::string(what) + ": expected [x, y, z, qx, qy, qz, qw]");
  }
  Eigen::Quaterniond q(n[6].as<double>(), n[3].as<double>(), n[4].as<double>(), n[5].as<double>());
  if (!(std::abs(q.norm() - 1.0) < 1e-3)) {
    throw std::runtime_error(std::string(what) + ": quaternion is not unit");
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(n[0].as<double>(), n[1].as<double>(), n[2].as<double>());
  if (!T.matrix().allFinite()) throw std::runtime_error(std::string(what) + ": not finite");
  return T;
}

/// The contact type of its short name (P2P, P2C, C2C); throws for anything else.
inline ContactType parseContactType(const std::string& s) {
  for (ContactType t :
       {ContactType::kPlanePlane, ContactType::kPlaneCurve, ContactType::kCurveCurve}) {
    if (s == shortName(t)) return t;
  }
  throw std::runtime_error("unknown contact type '" + s + "'");
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
