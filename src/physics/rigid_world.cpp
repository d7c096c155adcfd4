#include "geofusion/physics/rigid_world.h"

#include "geofusion/model/bullet_shapes.h"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <limits>
#include <map>

namespace geofusion {
namespace physics {
namespace {

btVector3 bt(const Eigen::Vector3d& v) {
  return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z()));
}

Eigen::Isometry3d fromBullet(const btTransform& t) {
  const btQuaternion q = t.getRotation();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(t.getOrigin().x(), t.getOrigin().y(), t.getOrigin().z());
  return T;
}

/// Bullet's collision margin of every hull, m (the generator's bodies are rounded by it).
constexpr double kHullMargin = 0.0005;

// Bullet rounds a convex hull outwards by its collision margin. The compound bodies' hulls are
// first moved inwards by the margin, so that the rounded shape is the model's own and objects that
// touch in the map touch in the simulation (not 1 mm into each other, pushed apart): each vertex
// by the vector whose dot product with every adjacent face's normal is the margin (least squares;
// at most 3 margins long at a sharp tip).
TriangleMesh shrunkByMargin(const TriangleMesh& hull, double margin) {
  std::vector<std::vector<Eigen::Vector3d>> normals(hull.vertices.size());
  for (const Eigen::Vector3i& t : hull.triangles) {
    const Eigen::Vector3d a = hull.vertices[t[0]].cast<double>(),
                          b = hull.vertices[t[1]].cast<double>(),
                          c = hull.vertices[t[2]].cast<double>();
    const Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() < 1e-12) continue;
    for (int k = 0; k < 3; ++k) normals[t[k]].push_back(n.normalized());
  }
  TriangleMesh out = hull;
  for (std::size_t i = 0; i < hull.vertices.size(); ++i) {
    if (normals[i].empty()) continue;
    Eigen::MatrixXd A(normals[i].size(), 3);
    for (std::size_t k = 0; k < normals[i].size(); ++k) A.row(k) = normals[i][k].transpose();
    Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(A);
    cod.setThreshold(0.05);
    Eigen::Vector3d inward = cod.solve(Eigen::VectorXd::Constant(A.rows(), margin));
    if (!inward.allFinite()) continue;
    if (inward.norm() > 3 * margin) inward *= 3 * margin / inward.norm();
    out.vertices[i] -= inward.cast<float>();
  }
  return out;
}

/// A compound body's shapes in the model frame: each hull moved inwards by the margin, each as
/// heavy as its volume (density x volume), and Bullet's centre of mass, principal axes and
/// inertia of the whole (each hull's box approximation moved to the centre). What the stability
/// check simulates and what an exported scene declares (compoundMassProperties).
struct ModelFrameCompound {
  ModelFrameCompound(const std::vector<TriangleMesh>& shapes, double density_kg_m3) {
    std::vector<btScalar> masses;
    btTransform identity;
    identity.setIdentity();
    for (const TriangleMesh& s : shapes) {
      hulls.push_back(
          bulletHull(shrunkByMargin(s, kHullMargin), Eigen::Vector3f::Zero(), kHullMargin));
      shape.addChildShape(identity, hulls.back().get());
      masses.push_back(btScalar(density_kg_m3 * std::max(enclosedVolume(s), 1e-9)));
      mass += masses.back();
    }
    principal.setIdentity();
    if (!masses.empty()) shape.calculatePrincipalAxisTransform(masses.data(), principal, inertia);
  }
  std::vector<std::unique_ptr<btConvexHullShape>> hulls;
  btCompoundShape shape{false};
  btScalar mass = 0;
  btTransform principal;
  btVector3 inertia{0, 0, 0};
};

}  // namespace

struct RigidWorld::Impl {
  struct Body {
    std::vector<std::unique_ptr<btConvexHullShape>> hulls;
    std::unique_ptr<btCompoundShape>
        compound;  ///< several shapes: the hulls about the principal axes
    std::unique_ptr<btDefaultMotionState> state;
    std::unique_ptr<btRigidBody> rigid;
    /// One hull: the body frame is the model frame shifted by `offset` (the vertices' mean).
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
    /// A compound: the body frame in the model frame (centre of mass, principal axes).
    Eigen::Isometry3d T_obj_body = Eigen::Isometry3d::Identity();
  };
  struct Static {
    std::unique_ptr<btBoxShape> shape;
    std::unique_ptr<btDefaultMotionState> state;
    std::unique_ptr<btRigidBody> rigid;
  };

  Impl()
      : dispatcher(&collision_config),
        world(&dispatcher, &broadphase, &solver, &collision_config) {}
  ~Impl() {
    for (Body& b : bodies) world.removeRigidBody(b.rigid.get());
    for (Static& s : statics) world.removeRigidBody(s.rigid.get());
  }

  // Mass 0 in the options: a compound of every shape, each as heavy as its volume.
  void makeCompound(const std::vector<TriangleMesh>& shapes, const RigidBodyOptions& o, Body* b,
                    btScalar* mass, btVector3* inertia) {
    ModelFrameCompound in_model_frame(shapes, o.density_kg_m3);
    *inertia = in_model_frame.inertia;
    *mass = in_model_frame.mass;
    b->T_obj_body = fromBullet(in_model_frame.principal);
    b->compound = std::make_unique<btCompoundShape>(false);
    const btTransform body_from_model = in_model_frame.principal.inverse();
    for (int i = 0; i < in_model_frame.shape.getNumChildShapes(); ++i)
      b->compound->addChildShape(body_from_model * in_model_frame.shape.getChildTransform(i),
                                 in_model_frame.shape.getChildShape(i));
    for (auto& hull : in_model_frame.hulls) b->hulls.push_back(std::move(hull));
  }

  btDefaultCollisionConfiguration collision_config;
  btCollisionDispatcher dispatcher;
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world;
  std::vector<Static> statics;
  std::vector<Body> bodies;
};

RigidWorld::RigidWorld(const Eigen::Vector3d& gravity) : impl_(std::make_unique<Impl>()) {
  impl_->world.setGravity(bt(gravity));
}

RigidWorld::~RigidWorld() = default;

void RigidWorld::addStaticBox(const Eigen::Isometry3d& T_world_box,
                              const Eigen::Vector3d& half_extents, double friction,
                              double rolling_friction) {
  Impl::Static s;
  s.shape = std::make_unique<btBoxShape>(bt(half_extents));
  s.state = std::make_unique<btDefaultMotionState>(toBullet(T_world_box));
  btRigidBody::btRigidBodyConstructionInfo info(0.0, s.state.get(), s.shape.get());
  info.m_friction = btScalar(friction);
  info.m_rollingFriction = btScalar(rolling_friction);
  info.m_spinningFriction = btScalar(rolling_friction);
  s.rigid = std::make_unique<btRigidBody>(info);
  impl_->world.addRigidBody(s.rigid.get());
  impl_->statics.push_back(std::move(s));
}

std::size_t RigidWorld::add(const std::vector<TriangleMesh>& shapes,
                            const Eigen::Isometry3d& T_world_obj, const RigidBodyOptions& o) {
  Impl::Body b;
  btScalar mass = 0;
  btVector3 inertia(0, 0, 0);
  btCollisionShape* shape = nullptr;
  if (o.mass_kg > 0.0 && !shapes.empty()) {
    const TriangleMesh& hull = shapes.front();
    Eigen::Vector3f c = Eigen::Vector3f::Zero();
    for (const auto& v : hull.vertices) c += v;
    c /= static_cast<float>(hull.vertices.size());
    b.offset = c.cast<double>();
    b.hulls.push_back(bulletHull(hull, c, kHullMargin));
    mass = btScalar(o.mass_kg);
    b.hulls.back()->calculateLocalInertia(mass, inertia);
    shape = b.hulls.back().get();
    b.state = std::make_unique<btDefaultMotionState>(
        toBullet(T_world_obj * Eigen::Translation3d(b.offset)));
  } else {
    impl_->makeCompound(shapes, o, &b, &mass, &inertia);
    shape = b.compound.get();
    b.state = std::make_unique<btDefaultMotionState>(toBullet(T_world_obj * b.T_obj_body));
  }
  btRigidBody::btRigidBodyConstructionInfo info(mass, b.state.get(), shape, inertia);
  info.m_friction = btScalar(o.friction);
  info.m_rollingFriction = btScalar(o.rolling_friction);
  info.m_spinningFriction = btScalar(o.rolling_friction);
  info.m_restitution = 0.0;
  info.m_linearDamping = btScalar(o.linear_damping);
  info.m_angularDamping = btScalar(o.angular_damping);
  b.rigid = std::make_unique<btRigidBody>(info);
  b.rigid->setActivationState(DISABLE_DEACTIVATION);
  impl_->world.addRigidBody(b.rigid.get());
  impl_->bodies.push_back(std::move(b));
  return impl_->bodies.size() - 1;
}

void RigidWorld::remove(std::size_t index) {
  impl_->world.removeRigidBody(impl_->bodies[index].rigid.get());
  impl_->bodies.erase(impl_->bodies.begin() + static_cast<std::ptrdiff_t>(index));
}

void RigidWorld::step(double dt_s) {
  impl_->world.stepSimulation(static_cast<btScalar>(dt_s), 1, static_cast<btScalar>(dt_s));
}

bool RigidWorld::moving(double linear_m_s, double angular_rad_s) const {
  for (const Impl::Body& b : impl_->bodies) {
    if (b.rigid->getLinearVelocity().length() > linear_m_s ||
        b.rigid->getAngularVelocity().length() > angular_rad_s)
      return true;
  }
  return false;
}

Eigen::Isometry3d RigidWorld::pose(std::size_t index) const {
  const Impl::Body& b = impl_->bodies[index];
  btTransform t;
  b.state->getWorldTransform(t);
  if (b.compound) return fromBullet(t) * b.T_obj_body.inverse();
  return fromBullet(t) * Eigen::Translation3d(-b.offset);
}

Eigen::Vector3d RigidWorld::centreOfMass(std::size_t index) const {
  btTransform t;
  impl_->bodies[index].state->getWorldTransform(t);
  return Eigen::Vector3d(t.getOrigin().x(), t.getOrigin().y(), t.getOrigin().z());
}

MassProperties compoundMassProperties(const std::vector<TriangleMesh>& shapes,
                                      double density_kg_m3) {
  const ModelFrameCompound compound(shapes, density_kg_m3);
  MassProperties p;
  p.mass_kg = compound.mass;
  p.T_obj_com = fromBullet(compound.principal);
  p.principal_inertia =
      Eigen::Vector3d(compound.inertia.x(), compound.inertia.y(), compound.inertia.z());
  return p;
}

std::size_t RigidWorld::size() const {
  return impl_->bodies.size();
}

std::vector<WorldContact> RigidWorld::contacts() const {
  auto index_of = [this](const btCollisionObject* o) {
    for (std::size_t i = 0; i < impl_->bodies.size(); ++i)
      if (impl_->bodies[i].rigid.get() == o) return static_cast<int>(i);
    return -1;  // a static box
  };
  // A compound body has a manifold per pair of its parts: one contact per pair of bodies.
  std::map<std::pair<int, int>, WorldContact> by_pair;
  btDispatcher& dispatcher = impl_->dispatcher;
  for (int m = 0; m < dispatcher.getNumManifolds(); ++m) {
    const btPersistentManifold* manifold = dispatcher.getManifoldByIndexInternal(m);
    int a = index_of(manifold->getBody0()), b = index_of(manifold->getBody1());
    if (manifold->getNumContacts() == 0 || a == b) continue;
    if (b < a) std::swap(a, b);
    auto [it, added] = by_pair.try_emplace({a, b});
    WorldContact& c = it->second;
    if (added) c.a = a, c.b = b, c.min_distance_m = std::numeric_limits<double>::infinity();
    for (int k = 0; k < manifold->getNumContacts(); ++k) {
      const btManifoldPoint& p = manifold->getContactPoint(k);
      c.normal_impulse_Ns += p.getAppliedImpulse();
      c.min_distance_m = std::min(c.min_distance_m, double(p.getDistance()));
      ++c.points;
    }
  }
  std::vector<WorldContact> out;
  for (const auto& [pair, c] : by_pair) out.push_back(c);
  return out;
}

}  // namespace physics
}  // namespace geofusion
