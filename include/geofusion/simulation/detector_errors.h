// The persistent part of a simulated 6D detector's errors. Real pose estimators looking at one
// object from nearby viewpoints repeat nearly the same mistake: a bias that drifts slowly along the
// trajectory (colour-only estimators mostly along the viewing ray), a look-alike class reported for
// a stretch of keyframes, an object missed for a stretch, a phantom object reported at a
// consistent pose. docs/dataset.md gives the presets' numbers and their sources.
#pragma once

#include <Eigen/Geometry>

#include <cstddef>
#include <random>
#include <vector>

namespace geofusion {

/// Magnitudes of the persistent errors; all zero (the default) is a detector whose errors are
/// independent from frame to frame.
struct PersistentErrorModel {
  double bias_translation_m = 0.0;           ///< std of an object's translation bias, per axis
  double bias_rotation_rad = 0.0;            ///< std of an object's rotation bias (each axis)
  double bias_correlation_keyframes = 30.0;  ///< correlation length of the bias (AR(1))
  /// std of an object's relative error along the viewing ray (share of the distance; colour-only
  /// estimators' depth ambiguity), and its correlation length: the sign holds for long stretches.
  double ray_depth_fraction = 0.0;
  double ray_correlation_keyframes = 120.0;
  /// Per keyframe, the chance that an object with a look-alike starts a stretch of this many
  /// keyframes in which it is reported as the look-alike.
  double swap_stretch_rate = 0.0;
  int swap_stretch_min = 20, swap_stretch_max = 60;
  /// Per keyframe, the chance that an object starts a stretch of this many keyframes in which the
  /// detector does not report it even when it is visible.
  double miss_stretch_rate = 0.0;
  int miss_stretch_min = 5, miss_stretch_max = 20;
  /// Phantom objects a scene: false objects beside a real one (a few centimetres off, any class),
  /// on for stretches of this many keyframes and off for as long, reported in `phantom_presence` of
  /// the keyframes of a stretch when their host object is visible.
  int phantoms = 0;
  int phantom_stretch_min = 40, phantom_stretch_max = 120;
  double phantom_presence = 0.8;
  /// How much the detection score follows the object's visibility (1: fully, as the independent
  /// presets; 0: a confident score whatever the error).
  double score_correctness = 1.0;

  bool enabled() const {
    return bias_translation_m > 0 || bias_rotation_rad > 0 || ray_depth_fraction > 0 ||
           swap_stretch_rate > 0 || miss_stretch_rate > 0 || phantoms > 0;
  }
};

/// The persistent error processes of one sequence: per object a bias (translation, rotation,
/// along the ray) following an AR(1) process over keyframes, swap and miss stretches; the
/// phantoms of the scene. Advanced once a keyframe with step().
class PersistentErrors {
 public:
  struct Phantom {
    int host = 0;                                            ///< the real object it sits beside
    Eigen::Vector3d offset_world = Eigen::Vector3d::Zero();  ///< from the host's position
    double yaw_rad = 0.0;  ///< about the world's z, from the host's orientation
    int class_pick = 0;    ///< which model class (an index the caller maps)
    int remaining = 0;     ///< keyframes left in the current on or off stretch
    bool on = false;
  };

  /// `has_look_alike[i]`: object i can be swapped (one entry an object); phantoms sit beside them.
  PersistentErrors(const PersistentErrorModel& model, std::vector<bool> has_look_alike,
                   std::mt19937& rng);

  /// One keyframe on: the biases move, stretches count down and start.
  void step(std::mt19937& rng);

  /// T_cam_obj with object i's bias: rotation and translation bias in the camera frame, then the
  /// error along the viewing ray.
  Eigen::Isometry3d apply(std::size_t i, const Eigen::Isometry3d& T_cam_obj) const;
  bool swapped(std::size_t i) const { return swap_left_[i] > 0; }
  bool missed(std::size_t i) const { return miss_left_[i] > 0; }
  /// Object i's current relative error along the ray (share of the distance).
  double rayFraction(std::size_t i) const { return ray_[i]; }
  const Eigen::Vector3d& translationBias(std::size_t i) const { return bias_t_[i]; }
  const std::vector<Phantom>& phantoms() const { return phantoms_; }
  const PersistentErrorModel& model() const { return model_; }

 private:
  int stretch(int lo, int hi, std::mt19937& rng) const;

  PersistentErrorModel model_;
  std::vector<bool> has_look_alike_;
  std::vector<Eigen::Vector3d> bias_t_, bias_r_;
  std::vector<double> ray_;
  std::vector<int> swap_left_, miss_left_;
  std::vector<Phantom> phantoms_;
};

}  // namespace geofusion
