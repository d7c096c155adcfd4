#include "geofusion/estimation/separation.h"

#include "geofusion/estimation/relations.h"
#include "geofusion/model/collision.h"
#include "geofusion/model/object_model.h"

namespace geofusion {
namespace {

// The body's hull vertex deepest under the plane, as a separation from the ground (none when it
// is shallower than `min_depth_m` or outside the plane's extent).
bool planeSeparation(const CollisionBody& body, int index, const SupportPlane& plane,
                     const Eigen::Isometry3d& T_world_ground, double min_depth_m, Separation* s) {
  if (depthThroughPlane(plane, *body.model, body.T_world_obj) <= min_depth_m) return false;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  const double lowest =
      hullHeightsAbove(*body.model, body.T_world_obj, plane.normal, plane.height, &point).first;
  s->object_a = -1, s->object_b = index;
  s->p_a = T_world_ground.inverse() * point;
  s->p_b = body.T_world_obj.inverse() * point;
  s->normal = plane.normal;
  s->depth = -lowest;
  return true;
}

}  // namespace

std::vector<Separation> findInterpenetrations(const std::vector<CollisionBody>& bodies,
                                              const SupportPlane* plane,
                                              const Eigen::Isometry3d& T_world_ground,
                                              double min_depth_m, HullCollider* collider,
                                              bool same_class_pairs, double hull_max_depth_m) {
  std::vector<Separation> out;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const CollisionBody& A = bodies[i];
    if (!A.model) continue;
    Separation s;
    if (plane && plane->valid &&
        planeSeparation(A, static_cast<int>(i), *plane, T_world_ground, min_depth_m, &s))
      out.push_back(s);
    for (std::size_t j = i + 1; j < bodies.size(); ++j) {
      const CollisionBody& B = bodies[j];
      // Two of a class that interpenetrate are likely one object twice: merging's to decide.
      if (!B.model || (!same_class_pairs && B.model->name == A.model->name)) continue;
      const double apart = (A.T_world_obj.translation() - B.T_world_obj.translation()).norm();
      if (apart > collider->reach(A.model) + collider->reach(B.model)) continue;
      HullContact c;
      if (hull_max_depth_m > 0.0)
        c = collider->hullContact(A.model, A.T_world_obj, B.model, B.T_world_obj);
      if (hull_max_depth_m <= 0.0 || c.depth > hull_max_depth_m)
        c = collider->partsContact(A.model, A.T_world_obj, B.model, B.T_world_obj);
      if (c.depth <= min_depth_m) continue;
      s.object_a = static_cast<int>(i), s.object_b = static_cast<int>(j);
      s.p_a = A.T_world_obj.inverse() * c.point;
      s.p_b = B.T_world_obj.inverse() * c.point;
      s.normal = c.normal;
      s.depth = c.depth;
      out.push_back(s);
    }
  }
  return out;
}

bool stillInterpenetrating(const Separation& s, const std::vector<CollisionBody>& bodies,
                           const SupportPlane& plane, double min_depth_m, HullCollider* collider) {
  const CollisionBody& b = bodies.at(static_cast<std::size_t>(s.object_b));
  if (!b.model) return false;
  if (s.object_a < 0) return depthThroughPlane(plane, *b.model, b.T_world_obj) > min_depth_m;
  const CollisionBody& a = bodies.at(static_cast<std::size_t>(s.object_a));
  return a.model &&
         collider->partsPenetration(a.model, a.T_world_obj, b.model, b.T_world_obj) > min_depth_m;
}

}  // namespace geofusion
