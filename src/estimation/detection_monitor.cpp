#include "geofusion/estimation/detection_monitor.h"

#include "geofusion/common/statistics.h"
#include "geofusion/estimation/scene_estimator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace geofusion {

namespace {

// The likely cause, from where the rejected detections lie against the observed surface.
std::string causeOf(const std::vector<double>& offsets_m) {
  if (offsets_m.size() < 5) return "check the depth image and the detector";
  const double m = percentile(offsets_m, 0.5);
  char text[200];
  if (std::abs(m) < 0.01) {
    std::snprintf(text, sizeof(text),
                  "they lie on the observed surface (%.1f cm) but do not fit its shape: check the "
                  "object models, the classes and the intrinsics",
                  100 * m);
  } else {
    // ray offset > 0: the observed surface is behind the detection, i.e. it sits in front.
    std::snprintf(text, sizeof(text),
                  "they lie %.1f cm %s the observed surface (median): check depth registration, "
                  "intrinsics or the detector's depth",
                  100 * std::abs(m), m < 0 ? "behind" : "in front of");
  }
  return text;
}

}  // namespace

std::string DetectionMonitor::add(const std::vector<DetectionReport>& detections) {
  KeyframeCounts k;
  for (const DetectionReport& d : detections) {
    if (d.decision == DetectionDecision::kSkipped || d.consistency < 0) continue;
    ++k.scored;
    if (d.consistency >= config_.inconsistent_below) continue;
    ++k.rejected;
    if (std::isfinite(d.ray_offset_m)) k.rejected_offsets_m.push_back(d.ray_offset_m);
  }
  window_.push_back(std::move(k));
  while (static_cast<int>(window_.size()) > std::max(1, config_.window_keyframes))
    window_.pop_front();
  int scored = 0, rejected = 0;
  std::vector<double> offsets;
  for (const KeyframeCounts& c : window_) {
    scored += c.scored;
    rejected += c.rejected;
    offsets.insert(offsets.end(), c.rejected_offsets_m.begin(), c.rejected_offsets_m.end());
  }
  if (scored < std::max(1, config_.min_detections)) return "";
  const double share = static_cast<double>(rejected) / scored;
  if (share < config_.warn_share) return "";
  char text[160];
  std::snprintf(text, sizeof(text),
                "%.0f%% of detections rejected as inconsistent with depth over the last %zu "
                "keyframes; ",
                100 * share, window_.size());
  return text + causeOf(offsets);
}

}  // namespace geofusion
