#include "geofusion/estimation/association.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace geofusion {
namespace {

double angleBetween(const Eigen::Matrix3d& R_a, const Eigen::Matrix3d& R_b) {
  return Eigen::AngleAxisd(R_a.transpose() * R_b).angle();
}

}  // namespace

double symmetricRotationError(const Symmetry& symmetry, const Eigen::Matrix3d& R_a,
                              const Eigen::Matrix3d& R_b) {
  switch (symmetry.type) {
    case Symmetry::Type::kContinuous: {
      const Eigen::Vector3d a = R_a * symmetry.axis, b = R_b * symmetry.axis;
      return std::acos(std::clamp(a.dot(b), -1.0, 1.0));
    }
    case Symmetry::Type::kDiscrete:
      return angleBetween(R_a, closestSymmetricEquivalent(symmetry, R_a, R_b));
    default: return angleBetween(R_a, R_b);
  }
}

Eigen::Matrix3d closestSymmetricEquivalent(const Symmetry& symmetry,
                                           const Eigen::Matrix3d& R_reference,
                                           const Eigen::Matrix3d& R_measured) {
  if (symmetry.type != Symmetry::Type::kDiscrete) return R_measured;
  Eigen::Matrix3d best = R_measured;
  double best_angle = angleBetween(R_reference, R_measured);
  for (const Eigen::Quaterniond& s : symmetry.rotations) {
    const Eigen::Matrix3d candidate = R_measured * s.toRotationMatrix();
    const double angle = angleBetween(R_reference, candidate);
    if (angle < best_angle) best_angle = angle, best = candidate;
  }
  return best;
}

double poseLikelihood(const Symmetry& symmetry, const Eigen::Isometry3d& T_predicted,
                      const Eigen::Isometry3d& T_measured, const AssociationConfig& config) {
  const double dt = (T_predicted.translation() - T_measured.translation()).norm();
  const double dq = symmetricRotationError(symmetry, T_predicted.linear(), T_measured.linear());
  const double m = dt * dt / (config.sigma_position_m * config.sigma_position_m) +
                   dq * dq / (config.sigma_rotation_rad * config.sigma_rotation_rad);
  return std::exp(-0.5 * m);
}

std::vector<int> solveAssignment(const Eigen::MatrixXd& cost) {
  const int rows = static_cast<int>(cost.rows()), cols = static_cast<int>(cost.cols());
  if (rows == 0 || cols == 0) return std::vector<int>(static_cast<std::size_t>(rows), -1);
  if (rows > cols) {  // the algorithm below needs rows <= cols
    const std::vector<int> by_col = solveAssignment(cost.transpose());
    std::vector<int> out(static_cast<std::size_t>(rows), -1);
    for (int c = 0; c < cols; ++c)
      if (by_col[c] >= 0) out[static_cast<std::size_t>(by_col[c])] = c;
    return out;
  }
  // Kuhn-Munkres with potentials (shortest augmenting paths), 1-based internally.
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> u(rows + 1, 0.0), v(cols + 1, 0.0);
  std::vector<int> p(cols + 1, 0), way(cols + 1, 0);
  for (int i = 1; i <= rows; ++i) {
    p[0] = i;
    int j0 = 0;
    std::vector<double> minv(cols + 1, inf);
    std::vector<char> used(cols + 1, 0);
    do {
      used[j0] = 1;
      const int i0 = p[j0];
      double delta = inf;
      int j1 = 0;
      for (int j = 1; j <= cols; ++j) {
        if (used[j]) continue;
        const double cur = cost(i0 - 1, j - 1) - u[i0] - v[j];
        if (cur < minv[j]) minv[j] = cur, way[j] = j0;
        if (minv[j] < delta) delta = minv[j], j1 = j;
      }
      for (int j = 0; j <= cols; ++j) {
        if (used[j])
          u[p[j]] += delta, v[j] -= delta;
        else
          minv[j] -= delta;
      }
      j0 = j1;
    } while (p[j0] != 0);
    do {
      const int j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0);
  }
  std::vector<int> out(static_cast<std::size_t>(rows), -1);
  for (int j = 1; j <= cols; ++j)
    if (p[j] > 0) out[static_cast<std::size_t>(p[j] - 1)] = j - 1;
  return out;
}

std::vector<int> associate(const Eigen::MatrixXd& likelihood, const AssociationConfig& config) {
  const int n = static_cast<int>(likelihood.rows()), m = static_cast<int>(likelihood.cols());
  std::vector<int> out(static_cast<std::size_t>(n), -1);
  if (n == 0) return out;
  if (!config.joint_assignment) {
    std::vector<char> taken(static_cast<std::size_t>(m), 0);
    for (int k = 0; k < n; ++k) {
      int best = -1;
      double best_l = config.eps_new;
      for (int j = 0; j < m; ++j) {
        if (likelihood(k, j) > best_l) best_l = likelihood(k, j), best = j;
      }
      // OMPO as the paper applies it: a taken object sends the later measurement to a new one.
      if (best >= 0 && !taken[static_cast<std::size_t>(best)]) {
        out[static_cast<std::size_t>(k)] = best;
        taken[static_cast<std::size_t>(best)] = 1;
      }
    }
    return out;
  }
  // Columns: the m objects, then one "new object" column per measurement (only its own).
  const double impossible = 1e9;
  const double new_cost = -std::log(std::max(config.eps_new, 1e-300));
  Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(n, m + n, impossible);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < m; ++j) {
      const double l = likelihood(k, j);
      if (l > config.eps_new) cost(k, j) = -std::log(l);
    }
    cost(k, m + k) = new_cost;
  }
  const std::vector<int> assignment = solveAssignment(cost);
  for (int k = 0; k < n; ++k) {
    const int j = assignment[static_cast<std::size_t>(k)];
    out[static_cast<std::size_t>(k)] = (j >= 0 && j < m && cost(k, j) < impossible) ? j : -1;
  }
  return out;
}

double falsePositiveScore(double best_consistency, int num_measurements) {
  return 1.0 - best_consistency / (1.0 + std::exp(-static_cast<double>(num_measurements)));
}

double boxCollisionRatio(const Eigen::Isometry3d& T_a, const Eigen::Vector3d& half_a,
                         const Eigen::Isometry3d& T_b, const Eigen::Vector3d& half_b) {
  const Eigen::Matrix3d A = T_a.linear(), B = T_b.linear();
  const Eigen::Vector3d d = T_b.translation() - T_a.translation();
  // Boxes whose bounding spheres are apart do not overlap (most pairs of a map: no axis test).
  const double reach = half_a.norm() + half_b.norm();
  if (d.squaredNorm() > reach * reach) return 0.0;
  // Extent (half length) of a box along a unit axis.
  auto radius = [](const Eigen::Matrix3d& R, const Eigen::Vector3d& half,
                   const Eigen::Vector3d& n) {
    return std::abs(R.col(0).dot(n)) * half.x() + std::abs(R.col(1).dot(n)) * half.y() +
           std::abs(R.col(2).dot(n)) * half.z();
  };
  std::array<Eigen::Vector3d, 15> axes;
  std::size_t n_axes = 0;
  for (int i = 0; i < 3; ++i) axes[n_axes++] = A.col(i), axes[n_axes++] = B.col(i);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const Eigen::Vector3d c = A.col(i).cross(B.col(j));
      if (c.norm() > 1e-6) axes[n_axes++] = c.normalized();
    }
  }
  double ratio = 1.0;
  for (std::size_t k = 0; k < n_axes; ++k) {
    const Eigen::Vector3d& n = axes[k];
    const double ra = radius(A, half_a, n), rb = radius(B, half_b, n);
    const double centre = d.dot(n);
    // Overlap of [-ra, ra] and [centre - rb, centre + rb].
    const double overlap = std::min(ra, centre + rb) - std::max(-ra, centre - rb);
    if (overlap <= 0.0) return 0.0;
    if (k < 6) ratio = std::min(ratio, overlap / std::max(1e-9, 2.0 * std::min(ra, rb)));
  }
  return std::min(1.0, ratio);
}

}  // namespace geofusion
