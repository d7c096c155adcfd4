// Small geometry helpers shared by the core tests: poses and primitive models with features.
#pragma once

#include "geofusion/model/mesh.h"
#include "geofusion/model/object_model.h"
#include "geofusion/model/surface_features.h"

#include <Eigen/Geometry>

#include <cmath>

namespace geofusion {
namespace test {

inline Eigen::Isometry3d at(double x, double y, double z,
                            const Eigen::Matrix3d& R = Eigen::Matrix3d::Identity()) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

inline Eigen::Matrix3d rot(double deg, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(deg * M_PI / 180.0, axis.normalized()).toRotationMatrix();
}

/// A box model centred on its frame, with surface features and evaluation points.
inline ObjectModel boxModel(double x, double y, double z) {
  ObjectModel m;
  m.name = "box";
  m.mesh = makeBox(Eigen::Vector3d(x, y, z));
  m.features = extractSurfaceFeatures(m.mesh);
  m.points = sampleSurfacePoints(m.mesh, 500);
  return m;
}

/// A can (cylinder along z, centred), continuous symmetry about z.
inline ObjectModel canModel(double radius, double height) {
  ObjectModel m;
  m.name = "can";
  m.mesh = makeCylinder(radius, height);
  m.features = extractSurfaceFeatures(m.mesh);
  m.points = sampleSurfacePoints(m.mesh, 500);
  m.symmetry.type = Symmetry::Type::kContinuous;
  return m;
}

}  // namespace test
}  // namespace geofusion
