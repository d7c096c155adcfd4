// The two optimisation stages of the paper ("Graph Optimization"), solved with Ceres:
// stage I over keyframe camera poses and object poses (odometry and object measurement factors,
// separate translation and rotation weights, symmetry axes left free), and stage II over object
// poses (object prior factors from stage I and P2P / P2C / C2C contact factors). Ceres stays in
// the .cpp; this header is light.
#pragma once

#include "geofusion/estimation/contacts.h"
#include "geofusion/model/object_model.h"

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace geofusion {

/// Robust loss of a factor: "none", "huber" or "cauchy", with its scale (on whitened residuals).
struct RobustLoss {
  std::string type = "huber";
  double scale = 2.0;
};

struct StageOneConfig {
  double measurement_sigma_position_m = 0.01;  ///< omega_p = 1 / sigma^2
  double measurement_sigma_rotation_rad = 0.08;
  double odometry_sigma_position_m = 0.003;  ///< between consecutive keyframes
  double odometry_sigma_rotation_rad = 0.004;
  RobustLoss measurement_loss;
  RobustLoss odometry_loss{"none", 1.0};
  int max_iterations = 10;     ///< warm-started: a few iterations converge
  int every_n_keyframes = 10;  ///< run every N keyframes (the paper: 10)
  /// Only the latest N keyframe poses are free (older ones fixed, their measurements still
  /// constrain the objects); 0 = all. Bounds the time of a run on long sequences.
  int window_keyframes = 30;
  /// Outside the window, marginalise instead of keeping: the cameras older than the window's
  /// anchor leave the problem, and their measurements (absolute measurements of the objects, the
  /// cameras being fixed) are folded into one prior per object (FoldedMeasurements); the noise
  /// adaptation looks at the window only. The fixed window's answer at a cost that depends on
  /// the window and the objects in view, not on the length of the run (issue 22).
  bool marginalise_outside_window = true;
  /// Noise adaptation (GeoFusion; variance component estimation from the residuals of each
  /// solve, used by the next): the odometry's variance scaled by a factor in
  /// [min_odometry_variance_factor, 1] (tighter only), each object's measurement variance by a
  /// factor in [1, max_object_variance_factor] (looser only), and a measurement whose squared
  /// whitened residual under its object's noise exceeds gate_chi2 (6 dof) left out of the next
  /// solve. An object whose detections carry a bias that changes with the viewpoint then cannot
  /// drag the cameras.
  bool adapt_noise = true;
  double min_odometry_variance_factor = 0.01;
  double max_object_variance_factor = 100.0;
  double gate_chi2 = 22.5;
  /// Issue 51 (symmetry_axis.h): the angle about a shape's continuous axis that the appearance
  /// does not share (a labelled can) follows the detections, their weighted circular mean,
  /// where they agree: mean resultant length (of the angles times the appearance's turns about
  /// the axis) at least axis_agreement_min (0.7: a circular spread of about 48 degrees). Off or
  /// scattered: the axis stays free, as for an untextured can.
  bool axis_from_detections = true;
  double axis_agreement_min = 0.7;
};

/// One object measurement z_t^k in stage I: keyframe t observes object j at T_cam_obj.
struct StageOneMeasurement {
  int keyframe = 0;
  int object = 0;
  Eigen::Isometry3d T_cam_obj = Eigen::Isometry3d::Identity();
  double weight = 1.0;  ///< scales the information (e.g. by geometric consistency)
  /// > 0: a depth-refined measurement, this translation std along the viewing ray (across it,
  /// measurement_sigma_position_m).
  double ray_sigma_m = 0.0;
};

/// How a stage's solve ended. Its result is used only when converged or stopped at the iteration
/// limit with a lower cost; a failed solve, or one that made the cost worse, leaves the poses as
/// they were (stage I) or at their priors (stage II), and the keyframe's results say so.
enum class SolveStatus {
  kNotRun,          ///< the stage did not run at this keyframe
  kConverged,       ///< Ceres converged
  kIterationLimit,  ///< stopped at max_iterations with a usable, not worse solution (used)
  kNothingToSolve,  ///< no factor to solve (stage II without contacts: the priors are the answer)
  kFailed,          ///< Ceres failed or the solution is not usable (not used)
  kCostIncreased,   ///< the final cost is above the initial one (not used)
  kBadInput,        ///< inconsistent sizes (not used)
};
const char* toString(SolveStatus status);
bool parseSolveStatus(const std::string& name, SolveStatus* status);  ///< toString's names
/// True for the outcomes whose result the estimator uses.
bool usable(SolveStatus status);

struct StageOneSummary {
  bool solved = false;  ///< the result was used (usable(status))
  SolveStatus status = SolveStatus::kNotRun;
  int iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  std::string message;
};

/// Object measurements whose cameras left stage I's window, folded into one prior on the object
/// in the map frame. A camera outside the window no longer moves, so each of its measurements is
/// an absolute measurement of the object: their translation terms sum exactly (information-
/// weighted mean, 3 x 3 information in the map frame, rays included), their rotations are
/// averaged (chordal mean after each is brought to the symmetric equivalent nearest a reference;
/// weights summed). The robust loss is not carried over (gated measurements have weight 0).
class FoldedMeasurements {
 public:
  /// Folds `m` (its keyframe's camera at `T_map_cam`); `R_reference` picks the symmetric
  /// equivalent (the object's current rotation). Measurements of weight 0 are counted only.
  void add(const Eigen::Isometry3d& T_map_cam, const StageOneMeasurement& m,
           const ObjectModel* model, const Eigen::Matrix3d& R_reference,
           const StageOneConfig& config);
  /// Folds another object's (or a saved map's) folded measurements in: the translation terms sum
  /// exactly, the other's mean rotation joins with its weight, brought to the symmetric
  /// equivalent of `model` nearest `R_reference` (the object's rotation, as for a measurement).
  void add(const FoldedMeasurements& other, const ObjectModel* model,
           const Eigen::Matrix3d& R_reference);
  /// Folded measurements given by what they amount to (a saved map's, map_store.h): the mean
  /// pose, the translation's information (map frame, 3 x 3, symmetric positive definite), the
  /// rotation's information (sum of w / sigma_r^2) and the number of measurements. Empty when
  /// the information is not positive or not finite.
  static FoldedMeasurements fromPrior(const Eigen::Isometry3d& mean,
                                      const Eigen::Matrix3d& translation_information,
                                      double rotation_information, int count);
  void clear() { *this = FoldedMeasurements(); }
  bool empty() const { return !(rotation_information_ > 0.0); }
  int count() const { return count_; }  ///< measurements folded (weight 0 included)
  const Eigen::Matrix3d& translationInformation() const { return translation_information_; }
  double rotationInformation() const { return rotation_information_; }
  /// The prior: mean pose, square-root information of the translation (map frame) and the
  /// rotation's weight (the factors' w_q).
  Eigen::Isometry3d mean() const;
  Eigen::Matrix3d translationSqrtInformation() const;
  double rotationWeight() const;
  /// Covariance of the folded estimate, [translation (map frame); rotation (map frame)].
  Eigen::Matrix<double, 6, 6> covariance() const;

 private:
  Eigen::Matrix3d translation_information_ = Eigen::Matrix3d::Zero();
  Eigen::Vector3d information_vector_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d rotation_sum_ = Eigen::Matrix3d::Zero();  ///< weighted sum of rotations
  double rotation_information_ = 0.0;                       ///< sum of w / sigma_r^2
  int count_ = 0;
};

/// The rotation `R_measured` brought to the symmetric equivalent nearest `R_reference`: the
/// closest discrete equivalent, or for a continuous symmetry the rotation about its axis.
Eigen::Matrix3d alignToReference(const Symmetry& symmetry, const Eigen::Matrix3d& R_reference,
                                 const Eigen::Matrix3d& R_measured);

/// Stage I. `T_map_cam` (in/out) are the keyframe camera poses, the first held fixed;
/// `T_odom_cam` the odometry the consecutive-keyframe factors come from; `T_map_obj` (in/out)
/// the object poses of `models` (for their symmetry). Warm-started from the values passed in.
/// Marginalising outside the window, the measurements of cameras before the window's anchor are
/// taken from `folded` (one per object, kept by the caller as cameras leave the window) and those
/// in `measurements` are ignored; with `folded` null they are folded here from `measurements`.
StageOneSummary optimizeStageOne(std::vector<Eigen::Isometry3d>* T_map_cam,
                                 const std::vector<Eigen::Isometry3d>& T_odom_cam,
                                 std::vector<Eigen::Isometry3d>* T_map_obj,
                                 const std::vector<const ObjectModel*>& models,
                                 const std::vector<StageOneMeasurement>& measurements,
                                 const StageOneConfig& config,
                                 const std::vector<FoldedMeasurements>* folded = nullptr);
/// The first keyframe stage I keeps in its problem for `n_keyframes` keyframes: the window's
/// anchor when marginalising outside a window, else 0.
std::size_t firstKeyframeInProblem(std::size_t n_keyframes, const StageOneConfig& config);

/// Squared whitened residuals (unit weight, no robust loss) of stage I's factors at the given
/// poses: one per odometry factor (keyframes i - 1, i) from `first_keyframe` on and one per
/// measurement, in order (0 for a measurement that refers to no keyframe or object). The
/// estimator's noise adaptation reads them.
struct StageOneResiduals {
  std::vector<double> odometry, measurements;
};
StageOneResiduals stageOneResiduals(const std::vector<Eigen::Isometry3d>& T_map_cam,
                                    const std::vector<Eigen::Isometry3d>& T_odom_cam,
                                    const std::vector<Eigen::Isometry3d>& T_map_obj,
                                    const std::vector<const ObjectModel*>& models,
                                    const std::vector<StageOneMeasurement>& measurements,
                                    const StageOneConfig& config, std::size_t first_keyframe = 0);

struct StageTwoConfig {
  double prior_sigma_position_m = 0.01;  ///< object prior factor (from stage I)
  double prior_sigma_rotation_rad = 0.06;
  /// Issue 50: an object's prior weighs by its evidence. An object measured n times holds to
  /// its stage I pose with weight sqrt(n / prior_full_weight_measurements) (its prior's sigmas
  /// divided by it; a mean of n measurements is that much surer), at most 1 and at least
  /// prior_min_weight: a candidate seen twice yields to one seen a hundred times instead of
  /// pushing it as hard (docs/stability.md). 0: every object the same weight (1).
  int prior_full_weight_measurements = 10;
  double prior_min_weight = 0.2;
  double contact_sigma_distance_m = 0.001;  ///< omega_p of the contact factors
  double contact_sigma_direction = 0.01;    ///< omega_q (unit-vector residual)
  RobustLoss contact_loss{"huber", 3.0};
  int max_iterations = 15;
  /// Which contacts beside the supports join stage II (the paper's has supports only). Side
  /// contacts stay out by default: between estimates a few millimetres apart they pull
  /// neighbours together and push partial duplicates apart before they can be merged (on
  /// `bench`, more flip-flops: docs/BENCHMARK.md).
  bool leaning_contacts = true;
  bool side_contacts = false;
  /// An object reaching through the support plane deeper than contacts.max_penetration_m has no
  /// contact with it (the relations stop there) and stage II would leave it in the table: true
  /// lifts it along the plane's normal onto the plane after stage II (issue 45: estimates 4-12
  /// cm through the table top on the bench suites, all of them false objects but one).
  bool lift_out_of_support = true;
  /// The local map: the relations, stage II and the overlap merge look at the objects seen in
  /// the latest N keyframes and those in contact with them; the others keep their pose and
  /// contacts until seen again (their cost stays bounded on long runs). 0: every object, every
  /// keyframe. The final solve of a run (finish) takes every object.
  int local_map_keyframes = 60;
  /// Issue 50: nothing interpenetrates. After the solve, estimates whose shapes (convex
  /// parts) interpenetrate deeper than separation_min_depth_m (HullCollider; the support plane:
  /// the hull) get a separation factor (factors/separation_factor.h: part along the contact
  /// normal by the depth plus separation_margin_m, weight 1 / separation_sigma_m) and stage II is
  /// solved again with them, up to separation_rounds times (0: off).
  int separation_rounds = 2;
  double separation_min_depth_m = 0.0005;
  double separation_margin_m = 0.0003;
  double separation_sigma_m = 0.0001;
  /// A separation carried from an earlier keyframe is dropped once the pair's stage I poses no
  /// longer interpenetrate (deeper than separation_min_depth_m): it was made for estimates
  /// since corrected, and would hold them off their measurements (docs/stability.md).
  bool separation_drop_stale = true;
  /// The final solve parts a pair whose hulls (the physical check's bodies) interpenetrate at
  /// most this deep as hulls; deeper, by their convex parts (a hull that deep spans a hollow the
  /// other object lies in). 0: convex parts only. Not when physics.convex_parts.
  double separation_hull_max_depth_m = 0.003;
  /// Issue 50, the paper's "physical relationship check": the final solve (finish(): the map a
  /// run ends with, a map saved with its final solve) puts the map into the stability check
  /// (EstimatorConfig::physics). An object the simulation drops (not interpenetrating at the
  /// start, then moving beyond the stability bounds but less than
  /// seat_max_translation_m and seat_max_rotation_deg: farther, it more likely stood on
  /// something the map lacks) has a support missing or wrong: the relations are found again
  /// with it where it came to rest, those contacts replace its own in stage II, and stage II
  /// seats it (solved again with its separation rounds, the dropped objects starting where they
  /// came to rest, each held back by its stage I prior); one with no contact there is left as it
  /// was, and nothing is seated without a support plane. The map's contacts stay as they were.
  /// Then checked again, at most seating_rounds times (0: off; docs/stability.md has the
  /// variants measured).
  int seating_rounds = 1;
  double seat_max_translation_m = 0.015;
  double seat_max_rotation_deg = 10.0;
  /// Issue 50: the map's contacts kept where the physics agrees. After seating, the final solve
  /// checks the map once more; a contact between two objects the check can judge (simulated,
  /// not starting inside another, standing) is kept when the pair bears on each other at rest
  /// (support, leaning: Bullet's normal force at least physics_min_force) or touches (side: a
  /// contact point within physics_side_max_distance_m); the others stay as found. Needs a
  /// support plane.
  bool physics_contacts = false;
  double physics_min_force = 0.01;  ///< N
  double physics_side_max_distance_m = 0.002;
};

/// A separation factor's data (SeparationFactor): the contact point in each body's frame (object
/// index -1 = the ground), the normal from a to b in the world and the depth to part by.
struct Separation {
  int object_a = -1, object_b = -1;
  Eigen::Vector3d p_a = Eigen::Vector3d::Zero(), p_b = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double depth = 0.0;
};

struct StageTwoSummary {
  bool solved = false;  ///< the result was used (usable(status))
  SolveStatus status = SolveStatus::kNotRun;
  int iterations = 0;
  int contacts = 0;
  int separations = 0;  ///< separation factors in the last solve
  double initial_cost = 0.0;
  double final_cost = 0.0;
};

/// Stage II over the object poses `T_world_obj` (in/out), pulled to `priors` and to the
/// `contacts` (object index -1 = the fixed support `ground`, may be null when no contact uses it)
/// and kept apart by `separations` (same indices), warm-started from `T_world_obj`. The objects
/// `held` (empty: none; else one flag per object) keep their poses: they are fixed ends of the
/// factors that reach them, and factors between fixed ends are left out (a re-solve of part of
/// the scene). `prior_weights` (empty: 1 each; else one per object, > 0) scale each prior's
/// information (priorWeight()).
StageTwoSummary optimizeStageTwo(std::vector<Eigen::Isometry3d>* T_world_obj,
                                 const std::vector<const ObjectModel*>& models,
                                 const std::vector<Eigen::Isometry3d>& priors,
                                 const std::vector<FeatureContact>& contacts,
                                 const PosedModel* ground, const StageTwoConfig& config,
                                 const std::vector<Separation>& separations = {},
                                 const std::vector<bool>& held = {},
                                 const std::vector<double>& prior_weights = {});

/// The weight of the stage II prior of an object measured `measurements` times
/// (StageTwoConfig::prior_full_weight_measurements).
double priorWeight(int measurements, const StageTwoConfig& config);

}  // namespace geofusion
