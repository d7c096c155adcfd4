#include "geofusion/model/collision.h"

#include "geofusion/model/fcl_hull.h"
#include "geofusion/model/object_model.h"

#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

#include <algorithm>
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

struct HullCollider::Impl {
  struct Part {
    std::shared_ptr<fcl::CollisionGeometryd> shape;
    Eigen::Vector3d centre;  ///< of the part's bounding sphere, model frame
    double radius = 0.0;
  };
  std::map<std::shared_ptr<const ObjectModel>, std::shared_ptr<fcl::CollisionGeometryd>> hulls;
  std::map<std::shared_ptr<const ObjectModel>, std::vector<Part>> parts;
  std::map<std::shared_ptr<const ObjectModel>, double> reach;
  std::shared_ptr<fcl::CollisionGeometryd> hull(const std::shared_ptr<const ObjectModel>& m) {
    auto it = hulls.find(m);
    if (it != hulls.end()) return it->second;
    auto g = fclHull(*m);
    hulls[m] = g;
    return g;
  }
  // The model's convex parts; a model with one part (or none made) has its hull, the same FCL
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
      p.shape = hull(m);
      sphere(collisionHullOf(*m), &p);
      out.push_back(p);
      return out;
    }
    for (const TriangleMesh& mesh : m->collision_parts) {
      Part p;
      p.shape = fclConvex(mesh);
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

namespace {

// `query` (penetration or distance) of the two models' hulls at their poses; 0 for a null model.
template <typename Impl, typename Query>
double onHulls(Impl* impl, const std::shared_ptr<const ObjectModel>& a,
               const Eigen::Isometry3d& T_world_a, const std::shared_ptr<const ObjectModel>& b,
               const Eigen::Isometry3d& T_world_b, Query query) {
  if (!a || !b) return 0.0;
  fcl::CollisionObjectd oa(impl->hull(a), fcl::Transform3d(T_world_a.matrix()));
  fcl::CollisionObjectd ob(impl->hull(b), fcl::Transform3d(T_world_b.matrix()));
  return query(&oa, &ob);
}

}  // namespace

double HullCollider::penetration(const std::shared_ptr<const ObjectModel>& a,
                                 const Eigen::Isometry3d& T_world_a,
                                 const std::shared_ptr<const ObjectModel>& b,
                                 const Eigen::Isometry3d& T_world_b) {
  return onHulls(impl_.get(), a, T_world_a, b, T_world_b, fclPenetration);
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
  const fcl::Transform3d Ta(T_world_a.matrix()), Tb(T_world_b.matrix());
  HullContact deepest;
  for (const Impl::Part& pa : impl_->partsOf(a)) {
    const Eigen::Vector3d ca = T_world_a * pa.centre;
    for (const Impl::Part& pb : impl_->partsOf(b)) {
      if ((ca - T_world_b * pb.centre).norm() > pa.radius + pb.radius) continue;  // apart
      fcl::CollisionObjectd oa(pa.shape, Ta), ob(pb.shape, Tb);
      const HullContact c = fclContact(&oa, &ob);
      if (c.depth > deepest.depth) deepest = c;
    }
  }
  return deepest;
}

double HullCollider::distance(const std::shared_ptr<const ObjectModel>& a,
                              const Eigen::Isometry3d& T_world_a,
                              const std::shared_ptr<const ObjectModel>& b,
                              const Eigen::Isometry3d& T_world_b) {
  return onHulls(impl_.get(), a, T_world_a, b, T_world_b, fclDistance);
}

}  // namespace geofusion
