// A Bullet rigid-body world of models on a static slab: the one place the package drives Bullet.
// The data generator settles its clutter scenes in it (simulation/clutter_scene.cpp) and the
// stability check drops a map's objects in it (stability.h). Bullet stays in rigid_world.cpp.
#pragma once
#include "geofusion/model/mesh.h"

#include <Eigen/Geometry>
#include <memory>
#include <vector>

namespace geofusion {
namespace physics {

/// How a body is made and how it moves.
struct RigidBodyOptions {
  /// > 0: the body is the first shape alone as one convex hull about its vertices' mean, with
  /// this mass (the generator's bodies). 0: a compound of every shape, mass density x volume,
  /// about its centre of mass and principal axes (the stability check's bodies).
  double mass_kg = 0.0;
  double density_kg_m3 = 600.0;
  double friction = 0.7;
  double rolling_friction = 0.002;  ///< rolling and spinning
  double linear_damping = 0.2;
  double angular_damping = 0.4;
};

/// A compound body's mass, centre of mass and inertia, as RigidWorld simulates it (options' mass
/// 0): mass density x volume of each convex shape, Bullet's principal axes and inertia.
struct MassProperties {
  double mass_kg = 0.0;
  /// Centre of mass and principal axes in the model frame.
  Eigen::Isometry3d T_obj_com = Eigen::Isometry3d::Identity();
  Eigen::Vector3d principal_inertia = Eigen::Vector3d::Zero();  ///< kg m^2, about those axes
};
MassProperties compoundMassProperties(const std::vector<TriangleMesh>& shapes,
                                      double density_kg_m3);

/// Two bodies touching after the latest step (Bullet's contact manifold of the pair): body
/// indices (-1: a static box), the normal impulse the solver applied at its points in that step
/// and the least distance between the shapes there (negative: overlapping).
struct WorldContact {
  int a = -1, b = -1;
  double normal_impulse_Ns = 0.0;
  double min_distance_m = 0.0;
  int points = 0;
};

class RigidWorld {
 public:
  explicit RigidWorld(const Eigen::Vector3d& gravity);
  ~RigidWorld();
  RigidWorld(const RigidWorld&) = delete;
  RigidWorld& operator=(const RigidWorld&) = delete;

  /// A static box (the table, the support plane's slab) at `T_world_box`, its centre.
  void addStaticBox(const Eigen::Isometry3d& T_world_box, const Eigen::Vector3d& half_extents,
                    double friction, double rolling_friction);
  /// A dynamic body of convex `shapes` (model frame) with its model frame at `T_world_obj`;
  /// returns its index (indices after a removed one shift down by one).
  std::size_t add(const std::vector<TriangleMesh>& shapes, const Eigen::Isometry3d& T_world_obj,
                  const RigidBodyOptions& options);
  void remove(std::size_t index);
  /// One fixed step of `dt_s`.
  void step(double dt_s);
  /// True when some body moves faster than these.
  bool moving(double linear_m_s, double angular_rad_s) const;
  /// The body's model frame in the world, and its centre of mass.
  Eigen::Isometry3d pose(std::size_t index) const;
  Eigen::Vector3d centreOfMass(std::size_t index) const;
  std::size_t size() const;
  /// The pairs with contact points after the latest step (points up to Bullet's contact
  /// breaking threshold apart, about 2 % of a body's size), a < b (a static box first, as -1).
  std::vector<WorldContact> contacts() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace physics
}  // namespace geofusion
