#include "geofusion/simulation/detector_errors.h"

#include <algorithm>
#include <cmath>

namespace geofusion {
namespace {

// One step of a stationary AR(1) process of standard deviation `sigma` and correlation length
// `length` (in steps): x <- rho x + sqrt(1 - rho^2) sigma n, rho = exp(-1 / length).
double ar1(double x, double sigma, double length, std::normal_distribution<double>& n,
           std::mt19937& rng) {
  const double rho = std::exp(-1.0 / std::max(1e-9, length));
  return rho * x + std::sqrt(1.0 - rho * rho) * sigma * n(rng);
}

}  // namespace

PersistentErrors::PersistentErrors(const PersistentErrorModel& model,
                                   std::vector<bool> has_look_alike, std::mt19937& rng)
    : model_(model),
      has_look_alike_(std::move(has_look_alike)),
      bias_t_(has_look_alike_.size(), Eigen::Vector3d::Zero()),
      bias_r_(has_look_alike_.size(), Eigen::Vector3d::Zero()),
      ray_(has_look_alike_.size(), 0.0),
      swap_left_(has_look_alike_.size(), 0),
      miss_left_(has_look_alike_.size(), 0) {
  const std::size_t objects = has_look_alike_.size();
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  // Start in the stationary distribution.
  for (std::size_t i = 0; i < objects; ++i) {
    bias_t_[i] = model.bias_translation_m * Eigen::Vector3d(n(rng), n(rng), n(rng));
    bias_r_[i] = model.bias_rotation_rad * Eigen::Vector3d(n(rng), n(rng), n(rng));
    ray_[i] = model.ray_depth_fraction * n(rng);
  }
  for (int k = 0; k < model.phantoms && objects > 0; ++k) {
    Phantom p;
    p.host = static_cast<int>(u(rng) * static_cast<double>(objects)) % static_cast<int>(objects);
    const double a = 2.0 * M_PI * u(rng);
    p.offset_world = (0.03 + 0.03 * u(rng)) * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0);
    p.yaw_rad = 2.0 * M_PI * u(rng);
    p.class_pick = static_cast<int>(u(rng) * 1e6);
    p.on = u(rng) < 0.5;
    p.remaining = stretch(model.phantom_stretch_min, model.phantom_stretch_max, rng);
    phantoms_.push_back(p);
  }
}

int PersistentErrors::stretch(int lo, int hi, std::mt19937& rng) const {
  std::uniform_int_distribution<int> d(std::max(1, lo), std::max(std::max(1, lo), hi));
  return d(rng);
}

void PersistentErrors::step(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const PersistentErrorModel& m = model_;
  for (std::size_t i = 0; i < bias_t_.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      bias_t_[i][k] =
          ar1(bias_t_[i][k], m.bias_translation_m, m.bias_correlation_keyframes, n, rng);
      bias_r_[i][k] = ar1(bias_r_[i][k], m.bias_rotation_rad, m.bias_correlation_keyframes, n, rng);
    }
    ray_[i] = ar1(ray_[i], m.ray_depth_fraction, m.ray_correlation_keyframes, n, rng);
    const bool can_swap = has_look_alike_[i];
    if (swap_left_[i] > 0) {
      --swap_left_[i];
    } else if (can_swap && u(rng) < m.swap_stretch_rate) {
      swap_left_[i] = stretch(m.swap_stretch_min, m.swap_stretch_max, rng);
    }
    if (miss_left_[i] > 0) {
      --miss_left_[i];
    } else if (u(rng) < m.miss_stretch_rate) {
      miss_left_[i] = stretch(m.miss_stretch_min, m.miss_stretch_max, rng);
    }
  }
  for (Phantom& p : phantoms_) {
    if (--p.remaining > 0) continue;
    p.on = !p.on;
    p.remaining = stretch(m.phantom_stretch_min, m.phantom_stretch_max, rng);
  }
}

Eigen::Isometry3d PersistentErrors::apply(std::size_t i, const Eigen::Isometry3d& T_cam_obj) const {
  Eigen::Isometry3d T = T_cam_obj;
  const Eigen::Vector3d& w = bias_r_[i];
  if (w.norm() > 0.0) T.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()) * T.linear();
  T.translation() += bias_t_[i];
  T.translation() *= 1.0 + ray_[i];  // along the viewing ray, a share of the distance
  return T;
}

}  // namespace geofusion
