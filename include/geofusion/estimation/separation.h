// Issue 50: estimates that interpenetrate after stage II. HullCollider (model/collision.h) on
// the objects' convex parts, and each hull's lowest point against the support plane; the result
// feeds stage II's separation factors (optimization.h, Separation).
#pragma once

#include "geofusion/estimation/optimization.h"

#include <Eigen/Geometry>

#include <memory>
#include <vector>

namespace geofusion {

class HullCollider;
struct ObjectModel;
struct SupportPlane;

/// An estimate as the collision check sees it.
struct CollisionBody {
  std::shared_ptr<const ObjectModel> model;
  Eigen::Isometry3d T_world_obj = Eigen::Isometry3d::Identity();
};

/// Every pair of `bodies` whose shapes (convex parts, HullCollider::partsContact: a hull that
/// spans a banana's curve is not the banana) interpenetrate, pairs of one class left out unless
/// `same_class_pairs` (likely one object twice: the merge decides on their interpenetration; the
/// final solve, after the last merge, parts them too), deeper than `min_depth_m`
/// (object indices into `bodies`), and every body deeper than that through a valid `plane` within
/// its extent (object_a -1; p_a in the frame `T_world_ground` of stage II's ground block), as
/// separations. A pair whose hulls interpenetrate at most `hull_max_depth_m` is parted as hulls
/// (the stability check's bodies) instead of parts; deeper, as parts (0: always as parts).
std::vector<Separation> findInterpenetrations(const std::vector<CollisionBody>& bodies,
                                              const SupportPlane* plane,
                                              const Eigen::Isometry3d& T_world_ground,
                                              double min_depth_m, HullCollider* collider,
                                              bool same_class_pairs = false,
                                              double hull_max_depth_m = 0.0);

/// Whether the pair of separation `s` (object indices into `bodies`, -1 the support `plane`)
/// still interpenetrates deeper than `min_depth_m` at the `bodies`' poses, measured as
/// findInterpenetrations finds it (convex parts; a hull through the plane). Stage II drops a
/// separation carried from an earlier keyframe once its pair's stage I poses do not
/// (stage_two.separation_drop_stale).
bool stillInterpenetrating(const Separation& s, const std::vector<CollisionBody>& bodies,
                           const SupportPlane& plane, double min_depth_m, HullCollider* collider);

}  // namespace geofusion
