// Physical stability of a map (issue 50): the estimated objects put into a rigid-body simulation
// (Bullet) as their collision shapes on the support plane, gravity on for a while, and how far
// each one moves. The paper's claim is a "geometrically stable scene"; penetration and gap are
// proxies, this asks the question itself. Used by the evaluation (every method and the ground
// truth) and by the runtime; Bullet stays inside stability.cpp.
#pragma once
#include "geofusion/model/mesh.h"

#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace geofusion {

struct ObjectModel;

namespace physics {

/// Settings of the check (YAML section `physics`, docs/parameters.md).
struct StabilityConfig {
  /// The bodies' shapes: false, each model's convex collision hull (what the data generator
  /// settles its scenes with and the evaluation's interpenetration measures); true, its convex
  /// parts (ObjectModel::collision_parts: a bowl's hollow, a drill's handle).
  bool convex_parts = false;
  double duration_s = 1.0;           ///< simulated time under gravity
  double time_step_s = 1.0 / 240.0;  ///< Bullet's fixed step
  double density_kg_m3 = 600.0;      ///< one density for every object: mass = density x volume
  double friction = 0.7;             ///< Coulomb friction of objects and the support plane
  double rolling_friction = 0.002;  ///< rolling and spinning friction (as the generator's settling)
  double linear_damping = 0.2;      ///< Bullet's velocity damping (as the generator's settling)
  double angular_damping = 0.4;
  double gravity_m_s2 = 9.81;           ///< along the map's gravity direction
  double stable_translation_m = 0.005;  ///< stable: the centre of mass moves less than this ...
  double stable_rotation_deg = 3.0;     ///< ... and the object turns less than this
  /// Objects deeper than this into another object or the plane at the start are reported apart:
  /// the simulator's push-out is not gravity.
  double start_penetration_m = 0.001;
  /// Two objects are in contact at the start (a candidate "pair") when their shapes are closer
  /// than this.
  double contact_distance_m = 0.002;
};

/// A numeric setting of StabilityConfig: its key in the `physics` section, its field, its allowed
/// range and what it means. The one list validate() and the configuration's table read.
struct StabilitySetting {
  const char* key;
  double StabilityConfig::*field;
  double min, max;
  const char* doc;
};
const std::vector<StabilitySetting>& stabilitySettings();

/// Empty when every setting is in range, else one message per setting out of range (naming it).
std::vector<std::string> validate(const StabilityConfig& config);

/// One object of the scene: its model (collision parts, or its collision hull) and pose.
struct StabilityBody {
  int id = -1;
  std::shared_ptr<const ObjectModel> model;
  Eigen::Isometry3d T_world_obj = Eigen::Isometry3d::Identity();
};

/// The support plane: points x with normal . x = offset, the normal pointing up (against gravity).
struct StabilityPlane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset = 0.0;
};

/// What happened to one object.
struct BodyMotion {
  int id = -1;
  bool simulated = false;            ///< false: no collision shape (see `problem`)
  std::string problem;               ///< why it was not simulated, empty when it was
  double translation_m = 0.0;        ///< of its centre of mass, over the simulated time
  double rotation_deg = 0.0;         ///< angle of its rotation over the simulated time
  double start_penetration_m = 0.0;  ///< deepest into another object or the plane at the start
  int penetrating_id = -1;        ///< the object it starts deepest in (kPlaneId: the plane), or -1
  bool interpenetrating = false;  ///< start_penetration_m above the setting: reported apart
  bool stable = false;            ///< simulated, not interpenetrating, below both bounds
  /// Where it came to rest: its model frame after the simulated time (the pose given when it
  /// was not simulated).
  Eigen::Isometry3d T_world_end = Eigen::Isometry3d::Identity();
};

constexpr int kPlaneId = -2;

/// Two bodies (or a body and the plane, kPlaneId) touching where the check left them: the
/// normal force between them in its last step (the solver's normal impulse over the step; 0 when
/// they touch without bearing on each other) and the least distance between their shapes there
/// (Bullet's contact points, up to its contact breaking threshold apart; negative: overlapping).
struct RestContact {
  int id_a = -1, id_b = -1;
  double normal_force_N = 0.0;
  double min_distance_m = 0.0;
};

/// The whole check, in the order of the bodies given.
struct StabilityResult {
  std::vector<BodyMotion> bodies;
  bool has_plane = false;  ///< false: a floor put under the lowest object (warnings say so)
  int simulated = 0;
  int interpenetrating = 0;  ///< of the simulated
  int checked = 0;           ///< simulated and not interpenetrating: the stability's denominator
  int stable = 0;
  double mean_translation_m = 0.0;  ///< over the checked
  double max_translation_m = 0.0;
  double max_rotation_deg = 0.0;
  /// The least stable pair: of the pairs in contact at the start (among the checked objects and
  /// the plane), the one whose relative displacement is the largest; ids, kPlaneId for the plane,
  /// -1 when there is no pair.
  std::pair<int, int> least_stable_pair{-1, -1};
  double least_stable_pair_m = 0.0;
  std::vector<std::string> warnings;       ///< bad input, named (the rest still checked)
  std::vector<RestContact> rest_contacts;  ///< where the bodies came to rest, pairs with points

  /// The pair's rest contact (either order; kPlaneId for the plane), null when they do not touch.
  const RestContact* restContact(int id_a, int id_b) const;

  double stableShare() const { return checked > 0 ? double(stable) / checked : 0.0; }
  const BodyMotion* find(int id) const;
};

/// The convex pieces a body is made of in the check (and in an exported scene): the model's
/// convex parts when `config.convex_parts` asks for them and it has them, else its collision hull;
/// empty when it has neither.
std::vector<TriangleMesh> bodyShapes(const ObjectModel& model, const StabilityConfig& config);

/// The plane bodies stand on when none is given: a floor (normal `up`) under the lowest point of
/// their shapes (`shapes[i]` in the model frame of `poses[i]`).
StabilityPlane floorUnder(const std::vector<std::vector<TriangleMesh>>& shapes,
                          const std::vector<Eigen::Isometry3d>& poses, const Eigen::Vector3d& up);

/// The direction of gravity a check uses: `gravity` normalised, else (zero or not finite) against
/// the plane's normal, else -z.
Eigen::Vector3d gravityDirection(const Eigen::Vector3d& gravity, const StabilityPlane* plane);

/// The static slab the bodies stand on: its top face the plane, centred under the bodies' world
/// boxes, 10 cm thick, reaching 0.5 m beyond them (at least 1 m from the centre).
struct SupportSlab {
  Eigen::Isometry3d T_world_box = Eigen::Isometry3d::Identity();  ///< its centre, z its normal
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();
};
SupportSlab supportSlab(const StabilityPlane& plane, const std::vector<Eigen::AlignedBox3d>& boxes);

/// Puts the bodies on the plane (a static slab whose top face is the plane; none given: a floor
/// under the lowest object, with a warning), gravity along `gravity` (normalised here; zero:
/// -plane normal), steps for `duration_s` and reports each body's motion.
StabilityResult checkStability(const std::vector<StabilityBody>& bodies,
                               const StabilityPlane* plane, const Eigen::Vector3d& gravity,
                               const StabilityConfig& config);

}  // namespace physics
}  // namespace geofusion
