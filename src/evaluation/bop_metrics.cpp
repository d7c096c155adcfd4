#include "geofusion/evaluation/bop_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace geofusion {

std::vector<Eigen::Isometry3d> symmetryTransformations(const Symmetry& symmetry,
                                                       const Eigen::Vector3d& centre,
                                                       int continuous_steps) {
  // About the centre: S x = c + R (x - c).
  auto about_centre = [&centre](const Eigen::Matrix3d& R) {
    Eigen::Isometry3d S = Eigen::Isometry3d::Identity();
    S.linear() = R;
    S.translation() = centre - R * centre;
    return S;
  };
  std::vector<Eigen::Isometry3d> out{Eigen::Isometry3d::Identity()};
  if (symmetry.type == Symmetry::Type::kDiscrete) {
    for (const Eigen::Quaterniond& q : symmetry.rotations)
      out.push_back(about_centre(q.normalized().toRotationMatrix()));
  } else if (symmetry.type == Symmetry::Type::kContinuous) {
    const int steps = std::max(2, continuous_steps);
    for (int i = 1; i < steps; ++i)
      out.push_back(
          about_centre(Eigen::AngleAxisd(2.0 * M_PI * i / steps, symmetry.axis.normalized())
                           .toRotationMatrix()));
  }
  return out;
}

BopModel bopModelOf(const ObjectModel& model) {
  BopModel out;
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3f& p : model.points) {
    out.points.push_back(p.cast<double>());
    box.extend(p.cast<double>());
  }
  if (out.points.empty()) return out;
  out.centre = box.center();
  double d2 = 0.0;
  for (std::size_t i = 0; i < out.points.size(); ++i)
    for (std::size_t j = i + 1; j < out.points.size(); ++j)
      d2 = std::max(d2, (out.points[i] - out.points[j]).squaredNorm());
  out.diameter_m = std::sqrt(d2);
  out.symmetries = symmetryTransformations(model.appearance_symmetry, out.centre);
  return out;
}

namespace {

// min over the symmetries S of max over the points of distance(T_est S x, T_true x), with
// `distance` of two camera-frame points; a symmetry stops as soon as it cannot beat the best.
template <typename Distance>
double minMaxOverSymmetries(const BopModel& model, const Eigen::Isometry3d& T_est,
                            const Eigen::Isometry3d& T_true, const Distance& distance) {
  double best = std::numeric_limits<double>::infinity();
  // The symmetry nearest the estimate's error first, so that the others stop early.
  std::vector<std::size_t> order(model.symmetries.size());
  std::vector<double> closeness(model.symmetries.size());
  const Eigen::Matrix3d E = T_true.linear().transpose() * T_est.linear();
  for (std::size_t s = 0; s < order.size(); ++s) {
    order[s] = s;
    closeness[s] = -(E.transpose() * model.symmetries[s].linear()).trace();
  }
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return closeness[a] < closeness[b]; });
  for (std::size_t s : order) {
    // As bop_toolkit: the symmetry on the truth's side (T_true S), the estimate as it is.
    const Eigen::Isometry3d T = T_true * model.symmetries[s];
    double worst = 0.0;
    for (const Eigen::Vector3d& x : model.points) {
      worst = std::max(worst, distance(T_est * x, T * x));
      if (worst >= best) break;
    }
    best = std::min(best, worst);
  }
  return best;
}

}  // namespace

double mssdError(const BopModel& model, const Eigen::Isometry3d& T_est,
                 const Eigen::Isometry3d& T_true) {
  if (model.points.empty()) return std::numeric_limits<double>::infinity();
  return minMaxOverSymmetries(
      model, T_est, T_true,
      [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return (a - b).norm(); });
}

double mspdError(const BopModel& model, const Eigen::Isometry3d& T_est,
                 const Eigen::Isometry3d& T_true, const PinholeIntrinsics& K) {
  if (model.points.empty()) return std::numeric_limits<double>::infinity();
  return minMaxOverSymmetries(model, T_est, T_true,
                              [&K](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
                                if (!(a.z() > 0.0) || !(b.z() > 0.0))
                                  return std::numeric_limits<double>::infinity();
                                return (K.project(a) - K.project(b)).norm();
                              });
}

}  // namespace geofusion
