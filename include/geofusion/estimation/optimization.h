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
  int window_keyframes = 60;
  /// Outside the window, marginalise instead of fixing: the older cameras and their measurements
  /// leave the problem, each object the window observes gets a prior at its current pose with
  /// their summed information, and the noise adaptation looks at the window only. Stage I's cost
  /// then depends on the window and the objects in view, not on the length of the run (issue
  /// 22; off until the benchmark shows the same accuracy as the full solve).
  bool marginalise_outside_window = false;
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

/// Stage I. `T_map_cam` (in/out) are the keyframe camera poses, the first held fixed;
/// `T_odom_cam` the odometry the consecutive-keyframe factors come from; `T_map_obj` (in/out)
/// the object poses of `models` (for their symmetry). Warm-started from the values passed in.
StageOneSummary optimizeStageOne(std::vector<Eigen::Isometry3d>* T_map_cam,
                                 const std::vector<Eigen::Isometry3d>& T_odom_cam,
                                 std::vector<Eigen::Isometry3d>* T_map_obj,
                                 const std::vector<const ObjectModel*>& models,
                                 const std::vector<StageOneMeasurement>& measurements,
                                 const StageOneConfig& config);

/// Squared whitened residuals (unit weight, no robust loss) of stage I's factors at the given
/// poses: one per odometry factor (keyframes i - 1, i) and one per measurement, in order (0 for a
/// measurement that refers to no keyframe or object). The estimator's noise adaptation reads them.
struct StageOneResiduals {
  std::vector<double> odometry, measurements;
};
StageOneResiduals stageOneResiduals(const std::vector<Eigen::Isometry3d>& T_map_cam,
                                    const std::vector<Eigen::Isometry3d>& T_odom_cam,
                                    const std::vector<Eigen::Isometry3d>& T_map_obj,
                                    const std::vector<const ObjectModel*>& models,
                                    const std::vector<StageOneMeasurement>& measurements,
                                    const StageOneConfig& config);

struct StageTwoConfig {
  double prior_sigma_position_m = 0.01;  ///< object prior factor (from stage I)
  double prior_sigma_rotation_rad = 0.06;
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
};

struct StageTwoSummary {
  bool solved = false;  ///< the result was used (usable(status))
  SolveStatus status = SolveStatus::kNotRun;
  int iterations = 0;
  int contacts = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
};

/// Stage II over the object poses `T_world_obj` (in/out), pulled to `priors` and to the
/// `contacts` (object index -1 = the fixed support `ground`, may be null when no contact uses it).
StageTwoSummary optimizeStageTwo(std::vector<Eigen::Isometry3d>* T_world_obj,
                                 const std::vector<const ObjectModel*>& models,
                                 const std::vector<Eigen::Isometry3d>& priors,
                                 const std::vector<FeatureContact>& contacts,
                                 const PosedModel* ground, const StageTwoConfig& config);

}  // namespace geofusion
