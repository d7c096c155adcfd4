// Which frames become keyframes: every N-th frame, or when the camera has moved or turned enough
// since the last keyframe (either rule, when both are set). The first frame always is one.
#pragma once

#include <Eigen/Geometry>

#include <algorithm>

namespace geofusion {

struct KeyframeSelectorConfig {
  int every_n_frames = 1;          ///< 1 = every frame (unless motion thresholds are set)
  double min_translation_m = 0.0;  ///< > 0: a keyframe once the camera moved this far ...
  double min_rotation_rad = 0.0;   ///< ... or turned this much since the last keyframe
};

class KeyframeSelector {
 public:
  explicit KeyframeSelector(const KeyframeSelectorConfig& config = {}) : config_(config) {}
  /// Whether the frame with this odometry camera pose is a keyframe (counts the frame).
  bool select(const Eigen::Isometry3d& T_odom_cam) {
    const int n = frames_++;
    bool take = !have_last_;
    if (!take) {
      const bool by_motion = config_.min_translation_m > 0.0 || config_.min_rotation_rad > 0.0;
      const Eigen::Isometry3d delta = last_.inverse() * T_odom_cam;
      if (by_motion) {
        take = (config_.min_translation_m > 0.0 &&
                delta.translation().norm() >= config_.min_translation_m) ||
               (config_.min_rotation_rad > 0.0 &&
                Eigen::AngleAxisd(delta.linear()).angle() >= config_.min_rotation_rad);
      }
      if (config_.every_n_frames > 1 || !by_motion) {
        take = take || (n - last_index_) >= std::max(1, config_.every_n_frames);
      }
    }
    if (take) {
      have_last_ = true;
      last_ = T_odom_cam;
      last_index_ = n;
    }
    return take;
  }
  void reset() { *this = KeyframeSelector(config_); }
  const KeyframeSelectorConfig& config() const { return config_; }

 private:
  KeyframeSelectorConfig config_;
  int frames_ = 0;
  int last_index_ = 0;
  bool have_last_ = false;
  Eigen::Isometry3d last_ = Eigen::Isometry3d::Identity();
};

}  // namespace geofusion
