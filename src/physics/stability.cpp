#include "geofusion/physics/stability.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "geofusion/model/collision.h"
#include "geofusion/model/object_model.h"
#include "geofusion/physics/rigid_world.h"

namespace geofusion {
namespace physics {
namespace {

/// Lowest point of the shapes along `up` in the world (for the plane's penetration and a floor).
double lowestAlong(const std::vector<TriangleMesh>& shapes, const Eigen::Isometry3d& T,
                   const Eigen::Vector3d& up) {
  double lowest = std::numeric_limits<double>::infinity();
  for (const TriangleMesh& s : shapes)
    for (const Eigen::Vector3f& v : s.vertices)
      lowest = std::min(lowest, up.dot(T * v.cast<double>()));
  return lowest;
}

RigidBodyOptions bodyOptions(const StabilityConfig& c) {
  RigidBodyOptions o;
  o.mass_kg = 0.0;  // density x volume, a compound of the convex parts
  o.density_kg_m3 = c.density_kg_m3;
  o.friction = c.friction;
  o.rolling_friction = c.rolling_friction;
  o.linear_damping = c.linear_damping;
  o.angular_damping = c.angular_damping;
  return o;
}

struct Prepared {
  std::size_t index = 0;  ///< into the bodies given
  std::vector<TriangleMesh> shapes;
  Eigen::AlignedBox3d box;  ///< world bounds of the shapes
};

Eigen::AlignedBox3d worldBox(const std::vector<TriangleMesh>& shapes, const Eigen::Isometry3d& T) {
  Eigen::AlignedBox3d box;
  for (const TriangleMesh& s : shapes)
    for (const Eigen::Vector3f& v : s.vertices) box.extend(T * v.cast<double>());
  return box;
}

/// Start state: each simulated body's deepest penetration (another body or the plane) and the
/// pairs in contact.
std::vector<std::pair<int, int>> startContacts(const std::vector<StabilityBody>& bodies,
                                               const std::vector<Prepared>& prepared,
                                               const StabilityPlane& plane,
                                               const StabilityConfig& config,
                                               std::vector<BodyMotion>* motions) {
  std::vector<std::pair<int, int>> pairs;  // indices into `prepared`, -1 for the plane
  HullCollider collider;
  const Eigen::Vector3d n = plane.normal.normalized();
  auto deepen = [&](BodyMotion& m, double depth, int other_id) {
    if (depth > m.start_penetration_m) {
      m.start_penetration_m = depth;
      m.penetrating_id = other_id;
    }
  };
  for (std::size_t a = 0; a < prepared.size(); ++a) {
    const StabilityBody& A = bodies[prepared[a].index];
    const double above = lowestAlong(prepared[a].shapes, A.T_world_obj, n) - plane.offset;
    deepen((*motions)[prepared[a].index], -above, kPlaneId);
    if (above < config.contact_distance_m) pairs.emplace_back(int(a), -1);
    for (std::size_t b = a + 1; b < prepared.size(); ++b) {
      const Eigen::AlignedBox3d grown(prepared[b].box.min().array() - config.contact_distance_m,
                                      prepared[b].box.max().array() + config.contact_distance_m);
      if (!grown.intersects(prepared[a].box)) continue;
      const StabilityBody& B = bodies[prepared[b].index];
      const double depth =
          config.convex_parts
              ? collider.partsPenetration(A.model, A.T_world_obj, B.model, B.T_world_obj)
              : collider.penetration(A.model, A.T_world_obj, B.model, B.T_world_obj);
      if (depth > 0.0) {
        deepen((*motions)[prepared[a].index], depth, B.id);
        deepen((*motions)[prepared[b].index], depth, A.id);
      }
      if (depth > 0.0 || collider.distance(A.model, A.T_world_obj, B.model, B.T_world_obj) <
                             config.contact_distance_m)
        pairs.emplace_back(int(a), int(b));
    }
  }
  return pairs;
}

double rotationDeg(const Eigen::Isometry3d& before, const Eigen::Isometry3d& after) {
  const Eigen::AngleAxisd delta(before.linear().transpose() * after.linear());
  return std::abs(delta.angle()) * 180.0 / M_PI;
}

/// The plane the bodies stand on: the one given, else a floor under the lowest body.
StabilityPlane supportOrFloor(const StabilityPlane* plane, const std::vector<StabilityBody>& bodies,
                              const std::vector<Prepared>& prepared, const Eigen::Vector3d& up,
                              StabilityResult* result) {
  result->has_plane = plane != nullptr;
  if (plane) return *plane;
  std::vector<std::vector<TriangleMesh>> shapes;
  std::vector<Eigen::Isometry3d> poses;
  for (const Prepared& p : prepared) {
    shapes.push_back(p.shapes);
    poses.push_back(bodies[p.index].T_world_obj);
  }
  result->warnings.push_back("no support plane: a floor is put under the lowest object");
  return floorUnder(shapes, poses, up);
}

/// Sums, bounds and the least stable pair over the checked bodies.
void summarise(const std::vector<Prepared>& prepared, const std::vector<std::pair<int, int>>& pairs,
               const std::vector<Eigen::Vector3d>& displacement, const StabilityConfig& config,
               StabilityResult* r) {
  double sum = 0.0;
  for (BodyMotion& m : r->bodies) {
    if (!m.simulated) continue;
    ++r->simulated;
    m.interpenetrating = m.start_penetration_m > config.start_penetration_m;
    if (m.interpenetrating) {
      ++r->interpenetrating;
      continue;
    }
    ++r->checked;
    m.stable = m.translation_m < config.stable_translation_m &&
               m.rotation_deg < config.stable_rotation_deg;
    r->stable += m.stable ? 1 : 0;
    sum += m.translation_m;
    r->max_translation_m = std::max(r->max_translation_m, m.translation_m);
    r->max_rotation_deg = std::max(r->max_rotation_deg, m.rotation_deg);
  }
  r->mean_translation_m = r->checked > 0 ? sum / r->checked : 0.0;
  for (const auto& [a, b] : pairs) {
    const BodyMotion& A = r->bodies[prepared[a].index];
    if (A.interpenetrating || (b >= 0 && r->bodies[prepared[b].index].interpenetrating)) continue;
    const Eigen::Vector3d other = b >= 0 ? displacement[b] : Eigen::Vector3d::Zero();
    const double relative = (displacement[a] - other).norm();
    if (r->least_stable_pair.first == -1 || relative > r->least_stable_pair_m) {
      r->least_stable_pair = {A.id, b >= 0 ? r->bodies[prepared[b].index].id : kPlaneId};
      r->least_stable_pair_m = relative;
    }
  }
}

}  // namespace

std::vector<TriangleMesh> bodyShapes(const ObjectModel& model, const StabilityConfig& config) {
  std::vector<TriangleMesh> shapes;
  if (config.convex_parts)
    for (const TriangleMesh& part : model.collision_parts)
      if (!part.empty()) shapes.push_back(part);
  if (shapes.empty()) {
    TriangleMesh hull = collisionHullOf(model);
    if (!hull.empty()) shapes.push_back(std::move(hull));
  }
  return shapes;
}

StabilityPlane floorUnder(const std::vector<std::vector<TriangleMesh>>& shapes,
                          const std::vector<Eigen::Isometry3d>& poses, const Eigen::Vector3d& up) {
  StabilityPlane floor;
  floor.normal = up;
  floor.offset = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < shapes.size() && i < poses.size(); ++i)
    floor.offset = std::min(floor.offset, lowestAlong(shapes[i], poses[i], up));
  if (!std::isfinite(floor.offset)) floor.offset = 0.0;
  return floor;
}

Eigen::Vector3d gravityDirection(const Eigen::Vector3d& gravity, const StabilityPlane* plane) {
  return gravity.allFinite() && gravity.norm() > 1e-9 ? gravity.normalized()
         : plane                                      ? -plane->normal.normalized()
                                                      : Eigen::Vector3d(0, 0, -1);
}

SupportSlab supportSlab(const StabilityPlane& plane,
                        const std::vector<Eigen::AlignedBox3d>& boxes) {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const Eigen::AlignedBox3d& b : boxes) centre += b.center();
  if (!boxes.empty()) centre /= double(boxes.size());
  double spread = 0.5;
  for (const Eigen::AlignedBox3d& b : boxes)
    spread = std::max(spread, (b.center() - centre).norm() + b.diagonal().norm());
  const double thickness = 0.1, half_extent = spread + 0.5;
  const Eigen::Vector3d n = plane.normal.normalized();
  SupportSlab slab;
  slab.T_world_box.linear() =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), n).toRotationMatrix();
  slab.T_world_box.translation() =
      centre - (n.dot(centre) - plane.offset) * n - 0.5 * thickness * n;
  slab.half_extents = Eigen::Vector3d(half_extent, half_extent, 0.5 * thickness);
  return slab;
}

const std::vector<StabilitySetting>& stabilitySettings() {
  using C = StabilityConfig;
  static const std::vector<StabilitySetting> settings = {
      {"duration_s", &C::duration_s, 1e-3, 60, "... simulated time under gravity, s"},
      {"time_step_s", &C::time_step_s, 1e-4, 0.02, "... Bullet's fixed step, s"},
      {"density_kg_m3", &C::density_kg_m3, 10, 20000,
       "... every object's density (mass = density x volume), kg/m^3"},
      {"friction", &C::friction, 0, 2, "... Coulomb friction of objects and support plane"},
      {"rolling_friction", &C::rolling_friction, 0, 0.1, "... rolling and spinning friction"},
      {"linear_damping", &C::linear_damping, 0, 0.99, "... Bullet's linear velocity damping"},
      {"angular_damping", &C::angular_damping, 0, 0.99, "... Bullet's angular velocity damping"},
      {"gravity_m_s2", &C::gravity_m_s2, 0.01, 50,
       "... gravity along the map's gravity direction, m/s^2"},
      {"stable_translation_m", &C::stable_translation_m, 1e-6, 1,
       "... stable: the centre of mass moves less than this, m"},
      {"stable_rotation_deg", &C::stable_rotation_deg, 1e-3, 180,
       "... and the object turns less than this, deg"},
      {"start_penetration_m", &C::start_penetration_m, 0, 1,
       "... objects deeper than this into another or the plane at the start are reported apart, "
       "m"},
      {"contact_distance_m", &C::contact_distance_m, 0, 1,
       "... objects closer than this at the start are a pair in contact, m"}};
  return settings;
}

std::vector<std::string> validate(const StabilityConfig& c) {
  std::vector<std::string> errors;
  for (const StabilitySetting& s : stabilitySettings()) {
    const double value = c.*s.field;
    if (value >= s.min && value <= s.max) continue;  // NaN fails both
    std::ostringstream m;
    m << "physics." << s.key << " = " << value << " is out of range (" << s.min
      << " <= x <= " << s.max << ")";
    errors.push_back(m.str());
  }
  return errors;
}

const RestContact* StabilityResult::restContact(int id_a, int id_b) const {
  for (const RestContact& c : rest_contacts)
    if ((c.id_a == id_a && c.id_b == id_b) || (c.id_a == id_b && c.id_b == id_a)) return &c;
  return nullptr;
}

const BodyMotion* StabilityResult::find(int id) const {
  for (const BodyMotion& m : bodies)
    if (m.id == id) return &m;
  return nullptr;
}

StabilityResult checkStability(const std::vector<StabilityBody>& bodies,
                               const StabilityPlane* plane, const Eigen::Vector3d& gravity,
                               const StabilityConfig& config) {
  StabilityResult result;
  result.warnings = validate(config);
  const StabilityConfig defaults;
  const StabilityConfig& c = result.warnings.empty() ? config : defaults;
  if (!result.warnings.empty()) result.warnings.push_back("physics: the defaults are used instead");
  const Eigen::Vector3d g = gravityDirection(gravity, plane);
  std::vector<Prepared> prepared;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    BodyMotion m;
    m.id = bodies[i].id;
    m.T_world_end = bodies[i].T_world_obj;
    std::vector<TriangleMesh> shapes;
    if (!bodies[i].model)
      m.problem = "no model";
    else if (!bodies[i].T_world_obj.matrix().allFinite())
      m.problem = "pose not finite";
    else if ((shapes = bodyShapes(*bodies[i].model, c)).empty())
      m.problem = "no collision shape";
    if (!m.problem.empty()) {
      result.warnings.push_back("object " + std::to_string(m.id) + " (" +
                                (bodies[i].model ? bodies[i].model->name : std::string("?")) +
                                "): " + m.problem + ", not simulated");
    } else {
      m.simulated = true;
      Prepared p{i, std::move(shapes), {}};
      p.box = worldBox(p.shapes, bodies[i].T_world_obj);
      prepared.push_back(std::move(p));
    }
    result.bodies.push_back(m);
  }
  if (prepared.empty()) return result;
  const StabilityPlane support = supportOrFloor(plane, bodies, prepared, -g, &result);
  const auto pairs = startContacts(bodies, prepared, support, c, &result.bodies);

  std::vector<Eigen::AlignedBox3d> boxes;
  for (const Prepared& p : prepared) boxes.push_back(p.box);
  RigidWorld world(g * c.gravity_m_s2);
  const SupportSlab slab = supportSlab(support, boxes);
  world.addStaticBox(slab.T_world_box, slab.half_extents, c.friction, c.rolling_friction);
  std::vector<Eigen::Vector3d> com_before;
  for (const Prepared& p : prepared) {
    world.add(p.shapes, bodies[p.index].T_world_obj, bodyOptions(c));
    com_before.push_back(world.centreOfMass(com_before.size()));
  }
  const int steps = static_cast<int>(std::ceil(c.duration_s / c.time_step_s - 1e-9));
  for (int i = 0; i < steps; ++i) world.step(c.time_step_s);
  std::vector<Eigen::Vector3d> displacement;
  for (std::size_t k = 0; k < prepared.size(); ++k) {
    BodyMotion& m = result.bodies[prepared[k].index];
    displacement.push_back(world.centreOfMass(k) - com_before[k]);
    m.translation_m = displacement.back().norm();
    m.T_world_end = world.pose(k);
    m.rotation_deg = rotationDeg(bodies[prepared[k].index].T_world_obj, m.T_world_end);
  }
  summarise(prepared, pairs, displacement, c, &result);
  auto id_of = [&](int k) {
    return k < 0 ? kPlaneId : result.bodies[prepared[static_cast<std::size_t>(k)].index].id;
  };
  for (const WorldContact& w : world.contacts())
    result.rest_contacts.push_back(
        {id_of(w.a), id_of(w.b), w.normal_impulse_Ns / c.time_step_s, w.min_distance_m});
  return result;
}

}  // namespace physics
}  // namespace geofusion
