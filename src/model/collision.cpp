#include "geofusion/model/collision.h"

#include "geofusion/model/bullet_shapes.h"
#include "geofusion/model/fcl_hull.h"
#include "geofusion/model/object_model.h"

#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

#include <BulletCollision/NarrowPhaseCollision/btGjkEpa2.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>

namespace geofusion {

TriangleMesh collisionHullOf(const ObjectModel& model) {
  return model.collision_hull.empty() ? collisionHull(model.mesh) : model.collision_hull;
}

namespace {

std::shared_ptr<fcl::CollisionGeometryd> fclConvex(const TriangleMesh& hull) {
  auto vertices = std::make_shared<std::vector<fcl::Vector3d>>();
  for (const auto& v : hull.vertices) vertices->push_back(v.cast<double>());
  auto faces = std::make_shared<std::vector<int>>();
  for (const auto& t : hull.triangles) {
    faces->push_back(3);
    faces->insert(faces->end(), {t[0], t[1], t[2]});
  }
  return std::make_shared<fcl::Convexd>(vertices, static_cast<int>(hull.triangles.size()), faces);
}

}  // namespace

std::shared_ptr<fcl::CollisionGeometryd> fclHull(const ObjectModel& model) {
  return fclConvex(collisionHullOf(model));
}

namespace {

// FCL's deepest contact of two collision objects (FCL: the normal points from a to b).
HullContact fclContact(fcl::CollisionObjectd* a, fcl::CollisionObjectd* b) {
  fcl::CollisionRequestd request(1, true);
  request.gjk_solver_type = fcl::GST_LIBCCD;
  fcl::CollisionResultd result;
  fcl::collide(a, b, request, result);
  HullContact out;
  for (std::size_t k = 0; k < result.numContacts(); ++k) {
    const fcl::Contactd& c = result.getContact(k);
    if (c.penetration_depth <= out.depth) continue;
    out.depth = c.penetration_depth;
    out.normal = c.normal.normalized();
    out.point = c.pos;
  }
  return out;
}

}  // namespace

double fclPenetration(fcl::CollisionObjectd* a, fcl::CollisionObjectd* b) {
  return fclContact(a, b).depth;
}

double fclDistance(fcl::CollisionObjectd* a, fcl::CollisionObjectd* b) {
  fcl::DistanceRequestd request;
  request.gjk_solver_type = fcl::GST_LIBCCD;
  fcl::DistanceResultd result;
  fcl::distance(a, b, request, result);
  return std::max(0.0, result.min_distance);
}

namespace {

std::shared_ptr<btConvexShape> btConvex(const TriangleMesh& hull) {
  return bulletHull(hull, Eigen::Vector3f::Zero(), 0.0);
}

// How far b must move along the world direction `n` to leave a: their supports' overlap along
// `n`. A parting translation for any direction; the penetration depth for the best one.
double overlapAlong(const btConvexShape& a, const btTransform& Ta, const btConvexShape& b,
                    const btTransform& Tb, const btVector3& n) {
  const btVector3 on_a = Ta * a.localGetSupportingVertexWithoutMargin(n * Ta.getBasis());
  const btVector3 on_b = Tb * b.localGetSupportingVertexWithoutMargin(-n * Tb.getBasis());
  return n.dot(on_a) - n.dot(on_b);
}

// The penetration of two posed convex shapes: the smallest translation that parts them, found by
// Bullet's GJK and EPA (FCL's libccd path gives MPR's depth along the line of the centres, deeper
// by up to centimetres: docs/stability.md). Bullet's EPA (single precision) can stop on a wrong
// face from a degenerate start: two boxes side by side, faces coplanar, started along their
// centres' line (2.2 mm for 5), or boxes with parallel faces started along an axis (141 mm for
// 80, its normal on a diagonal and the supports along it agreeing). So each answer is checked
// against the supports along its normal; when they disagree, EPA starts again along the axes, and
// an answer found that way is compared with one from a direction on no box axis, b turned by a
// milliradian (the depth still measured at the true poses); when no axis start agrees, up to
// three such starts. The depth is the supports' overlap along the best normal found, so never
// less than the true depth. Bullet gives the normal in a's frame and from b to a; here it is in
// the world and from a to b.
HullContact bulletContact(const btConvexShape& a, const Eigen::Isometry3d& T_world_a,
                          const btConvexShape& b, const Eigen::Isometry3d& T_world_b) {
  const btTransform Ta = toBullet(T_world_a), Tb = toBullet(T_world_b);
  const btVector3 centres = Tb.getOrigin() - Ta.getOrigin();
  const btVector3 starts[] = {centres.fuzzyZero() ? btVector3(0, 0, 1) : centres,
                              btVector3(0, 0, 1),
                              btVector3(1, 0, 0),
                              btVector3(0, 1, 0),
                              btVector3(0.36, 0.48, 0.80),  // unit, on no box's axis
                              btVector3(-0.80, 0.36, 0.48),
                              btVector3(0.48, -0.80, 0.36)};
  constexpr std::size_t kAxisStarts = 4;  // the centres and the three axes: b as it is
  const btTransform Tb_turned(Tb.getBasis() * btMatrix3x3(btQuaternion(starts[4], 1e-3)),
                              Tb.getOrigin());
  constexpr double kAgree = 2e-4;  // m: EPA's accuracy in single precision and then some
  HullContact best;
  best.depth = std::numeric_limits<double>::infinity();
  std::size_t last = std::size(starts);
  for (std::size_t k = 0; k < last; ++k) {
    const bool turned = k >= kAxisStarts;
    btGjkEpaSolver2::sResults r;
    if (!btGjkEpaSolver2::Penetration(&a, Ta, &b, turned ? Tb_turned : Tb, starts[k], r)) {
      if (!turned && r.status == btGjkEpaSolver2::sResults::Separated) return {};
      continue;  // GJK or EPA failed from this start
    }
    if (r.distance >= 0) {
      if (!turned) return {};
      continue;  // parted by the turn: no face from this start
    }
    const btVector3 n = -(Ta.getBasis() * r.normal).normalized();
    const double parting = overlapAlong(a, Ta, b, Tb, n);
    if (parting < best.depth) {
      const btVector3 mid = 0.5 * (r.witnesses[0] + r.witnesses[1]);
      best.depth = parting;
      best.normal = Eigen::Vector3d(n.x(), n.y(), n.z());
      best.point = Eigen::Vector3d(mid.x(), mid.y(), mid.z());
    }
    if (parting > -r.distance + kAgree) continue;  // EPA's face is not the supports'
    if (k == 0 || turned) break;                   // the centres' answer, or a turned one
    last = std::min(last, kAxisStarts + 1);        // an axis answer: one turned start to compare
    k = std::max(k, kAxisStarts - 1);
  }
  if (!(best.depth > 0.0) || !std::isfinite(best.depth)) return {};
  return best;
}

}  // namespace

struct HullCollider::Impl {
  struct Part {
    std::shared_ptr<btConvexShape> shape;
    Eigen::Vector3d centre;  ///< of the part's bounding sphere, model frame
    double radius = 0.0;
  };
  struct Hull {
    std::shared_ptr<fcl::CollisionGeometryd> fcl;  ///< for distances
    std::shared_ptr<btConvexShape> bullet;         ///< for penetrations
  };
  std::map<std::shared_ptr<const ObjectModel>, Hull> hulls;
  std::map<std::shared_ptr<const ObjectModel>, std::vector<Part>> parts;
  std::map<std::shared_ptr<const ObjectModel>, double> reach;
  const Hull& hull(const std::shared_ptr<const ObjectModel>& m) {
    auto it = hulls.find(m);
    if (it != hulls.end()) return it->second;
    const TriangleMesh mesh = collisionHullOf(*m);
    if (mesh.empty()) return hulls[m] = Hull{};  // no volume: nothing touches it
    return hulls[m] = Hull{fclConvex(mesh), btConvex(mesh)};
  }
  // The model's convex parts; a model with one part (or none made) has its hull, the same Bullet
  // shape penetration() uses.
  const std::vector<Part>& partsOf(const std::shared_ptr<const ObjectModel>& m) {
    auto it = parts.find(m);
    if (it != parts.end()) return it->second;
    std::vector<Part>& out = parts[m];
    auto sphere = [](const TriangleMesh& mesh, Part* p) {
      Eigen::Vector3f lo, hi;
      mesh.bounds(&lo, &hi);
      p->centre = (0.5f * (lo + hi)).cast<double>();
      for (const auto& v : mesh.vertices)
        p->radius = std::max(p->radius, (v.cast<double>() - p->centre).norm());
    };
    if (m->collision_parts.size() <= 1) {
      Part p;
      p.shape = hull(m).bullet;
      if (!p.shape) return out;  // no volume: no part
      sphere(collisionHullOf(*m), &p);
      out.push_back(p);
      return out;
    }
    for (const TriangleMesh& mesh : m->collision_parts) {
      Part p;
      p.shape = btConvex(mesh);
      sphere(mesh, &p);
      out.push_back(p);
    }
    return out;
  }
};

HullCollider::HullCollider() : impl_(std::make_unique<Impl>()) {}
HullCollider::~HullCollider() = default;

void HullCollider::prepare(const std::shared_ptr<const ObjectModel>& model) {
  if (!model) return;
  impl_->hull(model);
  impl_->partsOf(model);
}

double HullCollider::penetration(const std::shared_ptr<const ObjectModel>& a,
                                 const Eigen::Isometry3d& T_world_a,
                                 const std::shared_ptr<const ObjectModel>& b,
                                 const Eigen::Isometry3d& T_world_b) {
  return hullContact(a, T_world_a, b, T_world_b).depth;
}

HullContact HullCollider::hullContact(const std::shared_ptr<const ObjectModel>& a,
                                      const Eigen::Isometry3d& T_world_a,
                                      const std::shared_ptr<const ObjectModel>& b,
                                      const Eigen::Isometry3d& T_world_b) {
  if (!a || !b) return {};
  const Impl::Hull &ha = impl_->hull(a), &hb = impl_->hull(b);
  if (!ha.bullet || !hb.bullet) return {};
  return bulletContact(*ha.bullet, T_world_a, *hb.bullet, T_world_b);
}

double HullCollider::reach(const std::shared_ptr<const ObjectModel>& model) {
  if (!model) return 0.0;
  auto it = impl_->reach.find(model);
  if (it != impl_->reach.end()) return it->second;
  double r = 0.0;
  for (const auto& v : collisionHullOf(*model).vertices) r = std::max(r, double(v.norm()));
  impl_->reach[model] = r;
  return r;
}

double HullCollider::partsPenetration(const std::shared_ptr<const ObjectModel>& a,
                                      const Eigen::Isometry3d& T_world_a,
                                      const std::shared_ptr<const ObjectModel>& b,
                                      const Eigen::Isometry3d& T_world_b) {
  return partsContact(a, T_world_a, b, T_world_b).depth;
}

HullContact HullCollider::partsContact(const std::shared_ptr<const ObjectModel>& a,
                                       const Eigen::Isometry3d& T_world_a,
                                       const std::shared_ptr<const ObjectModel>& b,
                                       const Eigen::Isometry3d& T_world_b) {
  if (!a || !b) return {};
  HullContact deepest;
  for (const Impl::Part& pa : impl_->partsOf(a)) {
    const Eigen::Vector3d ca = T_world_a * pa.centre;
    for (const Impl::Part& pb : impl_->partsOf(b)) {
      if ((ca - T_world_b * pb.centre).norm() > pa.radius + pb.radius) continue;  // apart
      const HullContact c = bulletContact(*pa.shape, T_world_a, *pb.shape, T_world_b);
      if (c.depth > deepest.depth) deepest = c;
    }
  }
  return deepest;
}

double HullCollider::distance(const std::shared_ptr<const ObjectModel>& a,
                              const Eigen::Isometry3d& T_world_a,
                              const std::shared_ptr<const ObjectModel>& b,
                              const Eigen::Isometry3d& T_world_b) {
  if (!a || !b) return 0.0;
  const Impl::Hull &ha = impl_->hull(a), &hb = impl_->hull(b);
  if (!ha.fcl || !hb.fcl) return std::numeric_limits<double>::infinity();
  fcl::CollisionObjectd oa(ha.fcl, fcl::Transform3d(T_world_a.matrix()));
  fcl::CollisionObjectd ob(hb.fcl, fcl::Transform3d(T_world_b.matrix()));
  return fclDistance(&oa, &ob);
}

}  // namespace geofusion
