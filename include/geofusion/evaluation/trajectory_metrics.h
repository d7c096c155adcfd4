// Trajectory accuracy as the TUM RGB-D benchmark defines it (Sturm et al. 2012): absolute
// trajectory error after a rigid alignment (Umeyama, no scale; evo's `-a`) and relative pose
// error over a fixed time step, plus the TUM text format.
#pragma once

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace geofusion {

/// A true trajectory whose largest extent (standard deviation about its mean) is below this is a
/// camera held still: the alignment's rotation is not observable from its positions.
constexpr double kMinAlignmentSpreadM = 0.02;

/// Rigid transform T_true_est that best maps the estimated positions onto the true ones
/// (Eigen::umeyama without scale); only the offset of the means for a camera held still
/// (kMinAlignmentSpreadM; the real YCB-Video frames move 4 mm);
/// identity for fewer than 3 pairs. `rmse`: the residual RMSE.
Eigen::Isometry3d alignTrajectories(const std::vector<Eigen::Vector3d>& est,
                                    const std::vector<Eigen::Vector3d>& truth, double* rmse);

struct TrajectoryErrors {
  int pairs = 0;            ///< estimated poses with a true pose
  double ate_rmse_m = 0.0;  ///< after alignment
  double ate_mean_m = 0.0;
  double ate_max_m = 0.0;
  double rpe_delta_s = 1.0;  ///< time step of the relative errors
  int rpe_pairs = 0;
  double rpe_translation_rmse_m = 0.0;  ///< per rpe_delta_s
  double rpe_rotation_rmse_deg = 0.0;
  double length_m = 0.0;  ///< true path length over the paired poses
};

/// Errors of estimated poses against true poses given at the same stamps (pairs are taken where
/// stamps agree within `tolerance_s`).
TrajectoryErrors trajectoryErrors(const std::vector<double>& est_stamps,
                                  const std::vector<Eigen::Isometry3d>& est,
                                  const std::vector<double>& true_stamps,
                                  const std::vector<Eigen::Isometry3d>& truth,
                                  double rpe_delta_s = 1.0, double tolerance_s = 1e-3);

/// TUM format: "stamp tx ty tz qx qy qz qw" a line, with a comment header. Atomically written.
bool writeTum(const std::string& path, const std::vector<double>& stamps,
              const std::vector<Eigen::Isometry3d>& poses, std::string* error);

}  // namespace geofusion
