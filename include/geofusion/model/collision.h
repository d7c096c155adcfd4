// Collision geometry of the models: each model's convex collision hull and the queries the
// estimator (stage II's interpenetration check) and the simulation (settling scenes, ground-truth
// contacts) share.
#pragma once

#include "geofusion/model/mesh.h"

#include <Eigen/Geometry>

#include <memory>

namespace geofusion {

struct ObjectModel;

/// A model's collision hull: the one its ModelSet computed, or one made from its mesh for a model
/// built by hand.
TriangleMesh collisionHullOf(const ObjectModel& model);

/// Where two posed hulls interpenetrate: `depth` (0 when apart; the smallest translation that
/// parts them), the world `normal` along which b leaves a (from a to b), and the contact `point`
/// in the world.
struct HullContact {
  double depth = 0.0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
};

/// Interpenetration depth of two posed models' convex collision hulls (0 when apart): Bullet's
/// GJK-EPA; distances: FCL (libccd's GJK). FCL's own penetration (libccd's MPR, along the line of
/// the centres) overstates it by up to centimetres (docs/stability.md). Keeps each model's shapes
/// (keyed by the model, which it keeps alive) for repeated use.
class HullCollider {
 public:
  HullCollider();
  ~HullCollider();
  double penetration(const std::shared_ptr<const ObjectModel>& a,
                     const Eigen::Isometry3d& T_world_a,
                     const std::shared_ptr<const ObjectModel>& b,
                     const Eigen::Isometry3d& T_world_b);
  /// Interpenetration of the two models' shapes: the deepest over pairs of their convex parts
  /// (ObjectModel::collision_parts), what penetration() gives for two models their hulls fit.
  double partsPenetration(const std::shared_ptr<const ObjectModel>& a,
                          const Eigen::Isometry3d& T_world_a,
                          const std::shared_ptr<const ObjectModel>& b,
                          const Eigen::Isometry3d& T_world_b);
  /// The deepest contact over pairs of the two models' convex parts (as partsPenetration()).
  HullContact partsContact(const std::shared_ptr<const ObjectModel>& a,
                           const Eigen::Isometry3d& T_world_a,
                           const std::shared_ptr<const ObjectModel>& b,
                           const Eigen::Isometry3d& T_world_b);
  /// The contact of the two models' convex hulls (as penetration()).
  HullContact hullContact(const std::shared_ptr<const ObjectModel>& a,
                          const Eigen::Isometry3d& T_world_a,
                          const std::shared_ptr<const ObjectModel>& b,
                          const Eigen::Isometry3d& T_world_b);
  /// The radius of the model hull's bounding sphere about the model frame's origin (a cheap
  /// test before contact()).
  double reach(const std::shared_ptr<const ObjectModel>& model);
  /// Builds the model's hull and parts shapes now (at start, not at the first contact check).
  void prepare(const std::shared_ptr<const ObjectModel>& model);
  /// Distance between the two hulls, 0 when they touch or intersect. A model without a hull (a
  /// mesh without volume, which model sets refuse) touches nothing: no depth, infinite distance.
  double distance(const std::shared_ptr<const ObjectModel>& a, const Eigen::Isometry3d& T_world_a,
                  const std::shared_ptr<const ObjectModel>& b, const Eigen::Isometry3d& T_world_b);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace geofusion
