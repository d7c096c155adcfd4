// The frame-by-frame (FbF) view of the paper's baseline: each frame's detections, checked and
// placed in a world frame (odometry or map) through the camera pose, with no fusion over time.
#pragma once

#include "geofusion/common/measurement.h"
#include "geofusion/common/pose_validation.h"

#include <array>
#include <cstddef>
#include <set>
#include <string>
#include <vector>

namespace geofusion {

/// Why a detection was not used.
enum class SkipReason {
  kNonFiniteTranslation = 0,
  kNonFiniteRotation,
  kZeroQuaternion,
  kNonUnitQuaternion,
  kEmptyClass,
  kBadScore,
  kLowScore,
  kOutOfRange,
  kUnknownClass,  ///< a class the model set does not have
  kOverCap,       ///< beyond max_detections of the frame (the lowest scores go first)
  kCount
};

const char* toString(SkipReason reason);

/// Counts of accepted and skipped detections, by reason.
struct DetectionTally {
  std::size_t frames = 0;
  std::size_t accepted = 0;
  std::array<std::size_t, static_cast<std::size_t>(SkipReason::kCount)> skipped{};

  std::size_t totalSkipped() const;
  void add(const DetectionTally& other);
  /// e.g. "12 frames, 40 detections used, 3 skipped (2 non-unit quaternion, 1 low score)".
  std::string summary() const;
};

/// A detection placed in the world frame.
struct WorldDetection {
  ObjectMeasurement measurement;                                  ///< camera-frame measurement
  Eigen::Isometry3d T_world_obj = Eigen::Isometry3d::Identity();  ///< object pose in world frame
};

class FrameByFrame {
 public:
  struct Config {
    /// Detections scoring below this are skipped (kLowScore).
    double min_score = 0.0;
    /// Detections farther than this from the camera centre are skipped (kOutOfRange), metres.
    double max_range_m = 10.0;
    /// Tolerance on | |q| - 1 | of incoming quaternions.
    double unit_quaternion_tolerance = kUnitQuaternionTolerance;
    /// A frame's usable detections beyond this many are dropped, the lowest scores first
    /// (kOverCap): a detector gone wild cannot stall the estimator.
    int max_detections = 100;
  };

  FrameByFrame() = default;
  explicit FrameByFrame(const Config& config) : config_(config) {}

  const Config& config() const { return config_; }
  void setConfig(const Config& config) { config_ = config; }

  /// The classes the estimator knows (its model set); a detection of another class is skipped
  /// (kUnknownClass). Empty (the default): every class passes.
  void setKnownClasses(std::set<std::string> classes) { known_classes_ = std::move(classes); }

  /// Checks one raw detection; on success fills `out` and returns true, else sets `reason`.
  bool check(const RawDetection& raw, ObjectMeasurement* out, SkipReason* reason) const;

  /// Checks all detections of a frame, keeps at most max_detections of the usable ones (the
  /// highest scores) and places them in the world frame through the camera pose T_world_cam.
  /// Adds one frame and the per-detection outcomes to `tally`.
  std::vector<WorldDetection> process(const std::vector<RawDetection>& detections,
                                      const Eigen::Isometry3d& T_world_cam,
                                      DetectionTally* tally) const;

 private:
  Config config_;
  std::set<std::string> known_classes_;
};

}  // namespace geofusion
