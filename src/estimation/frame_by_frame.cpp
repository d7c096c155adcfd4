#include "geofusion/estimation/frame_by_frame.h"

#include "geofusion/common/ingestion.h"
#include "geofusion/common/pose_validation.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

namespace geofusion {

const char* toString(SkipReason reason) {
  switch (reason) {
    case SkipReason::kNonFiniteTranslation: return "non-finite translation";
    case SkipReason::kNonFiniteRotation: return "non-finite quaternion";
    case SkipReason::kZeroQuaternion: return "zero quaternion";
    case SkipReason::kNonUnitQuaternion: return "non-unit quaternion";
    case SkipReason::kEmptyClass: return "empty class name";
    case SkipReason::kBadScore: return "score not in [0, 1]";
    case SkipReason::kLowScore: return "score below min_score";
    case SkipReason::kOutOfRange: return "beyond max_range_m";
    case SkipReason::kUnknownClass: return "unknown class";
    case SkipReason::kOverCap: return "over max_detections";
    case SkipReason::kCount: break;
  }
  return "unknown";
}

std::size_t DetectionTally::totalSkipped() const {
  std::size_t n = 0;
  for (std::size_t s : skipped) n += s;
  return n;
}

void DetectionTally::add(const DetectionTally& other) {
  frames += other.frames;
  accepted += other.accepted;
  for (std::size_t i = 0; i < skipped.size(); ++i) skipped[i] += other.skipped[i];
}

std::string DetectionTally::summary() const {
  std::ostringstream os;
  os << frames << " frames, " << accepted << " detections used, " << totalSkipped() << " skipped";
  if (totalSkipped() > 0) os << " (" << reasonsLine(countsByReason<SkipReason>(skipped)) << ")";
  return os.str();
}

namespace {
SkipReason toSkipReason(PoseStatus status) {
  switch (status) {
    case PoseStatus::kNonFiniteTranslation: return SkipReason::kNonFiniteTranslation;
    case PoseStatus::kNonFiniteRotation: return SkipReason::kNonFiniteRotation;
    case PoseStatus::kZeroQuaternion: return SkipReason::kZeroQuaternion;
    default: return SkipReason::kNonUnitQuaternion;
  }
}
}  // namespace

bool FrameByFrame::check(const RawDetection& raw, ObjectMeasurement* out,
                         SkipReason* reason) const {
  const PoseStatus status =
      checkPose(raw.position_cam, raw.orientation_cam, config_.unit_quaternion_tolerance);
  if (status != PoseStatus::kValid) {
    *reason = toSkipReason(status);
    return false;
  }
  if (raw.class_name.empty()) {
    *reason = SkipReason::kEmptyClass;
    return false;
  }
  if (!known_classes_.empty() && known_classes_.count(raw.class_name) == 0) {
    *reason = SkipReason::kUnknownClass;
    return false;
  }
  if (!std::isfinite(raw.score) || raw.score < 0.0 || raw.score > 1.0) {
    *reason = SkipReason::kBadScore;
    return false;
  }
  if (raw.score < config_.min_score) {
    *reason = SkipReason::kLowScore;
    return false;
  }
  if (raw.position_cam.norm() > config_.max_range_m) {
    *reason = SkipReason::kOutOfRange;
    return false;
  }
  out->class_name = raw.class_name;
  out->class_id = raw.class_id;
  out->score = raw.score;
  out->T_cam_obj = makeIsometry(raw.position_cam, raw.orientation_cam);
  out->box = raw.box;
  return true;
}

std::vector<WorldDetection> FrameByFrame::process(const std::vector<RawDetection>& detections,
                                                  const Eigen::Isometry3d& T_world_cam,
                                                  DetectionTally* tally) const {
  std::vector<WorldDetection> result;
  result.reserve(detections.size());
  if (tally) ++tally->frames;
  for (const RawDetection& raw : detections) {
    WorldDetection wd;
    SkipReason reason = SkipReason::kCount;
    if (!check(raw, &wd.measurement, &reason)) {
      if (tally) ++tally->skipped[static_cast<std::size_t>(reason)];
      continue;
    }
    wd.T_world_obj = T_world_cam * wd.measurement.T_cam_obj;
    result.push_back(std::move(wd));
  }
  const std::size_t cap = static_cast<std::size_t>(std::max(0, config_.max_detections));
  if (result.size() > cap) {
    // The highest scores stay, in their original order.
    std::vector<std::size_t> order(result.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return result[a].measurement.score > result[b].measurement.score;
    });
    std::vector<bool> keep(result.size(), false);
    for (std::size_t i = 0; i < cap; ++i) keep[order[i]] = true;
    std::vector<WorldDetection> kept;
    kept.reserve(cap);
    for (std::size_t i = 0; i < result.size(); ++i)
      if (keep[i]) kept.push_back(std::move(result[i]));
    if (tally)
      tally->skipped[static_cast<std::size_t>(SkipReason::kOverCap)] += result.size() - cap;
    result = std::move(kept);
  }
  if (tally) tally->accepted += result.size();
  return result;
}

}  // namespace geofusion
