#include "geofusion/common/ingestion.h"

#include <algorithm>
#include <limits>
#include <sstream>

namespace geofusion {

const char* toString(FrameDrop reason) {
  switch (reason) {
    case FrameDrop::kNone: return "used";
    case FrameDrop::kOutOfOrder: return "out of order";
    case FrameDrop::kStale: return "stale";
    case FrameDrop::kUnsynchronised: return "unsynchronised";
    case FrameDrop::kNoOdometry: return "no camera pose";
    case FrameDrop::kOdometryGap: return "odometry gap";
    case FrameDrop::kBadDepth: return "unusable depth";
    case FrameDrop::kBadCameraInfo: return "unusable camera_info";
    case FrameDrop::kQueueOverflow: return "queue overflow";
    case FrameDrop::kCount: break;
  }
  return "unknown";
}

std::size_t FrameDropCounts::total() const {
  std::size_t n = 0;
  for (std::size_t c : count) n += c;
  return n;
}

std::string reasonsLine(const std::vector<std::pair<std::string, std::size_t>>& counts) {
  std::ostringstream os;
  for (std::size_t i = 0; i < counts.size(); ++i)
    os << (i ? ", " : "") << counts[i].second << " " << counts[i].first;
  return os.str();
}

std::string FrameDropCounts::summary() const {
  if (total() == 0) return "none dropped";
  return std::to_string(total()) + " dropped (" + reasonsLine(countsByReason<FrameDrop>(count)) +
         ")";
}

std::size_t unsynchronisedFrames(const std::vector<std::size_t>& message_counts,
                                 std::size_t synchronised_sets) {
  const std::size_t most =
      message_counts.empty() ? 0 : *std::max_element(message_counts.begin(), message_counts.end());
  return most > synchronised_sets ? most - synchronised_sets : 0;
}

void OdometryTimeline::add(double stamp_s) {
  // Time jumped back (a looping bag): the samples of the old timeline say nothing any more.
  if (!stamps_.empty() && stamp_s + std::min(jump_back_s_, horizon_s_) < stamps_.back())
    stamps_.clear();
  stamps_.insert(std::upper_bound(stamps_.begin(), stamps_.end(), stamp_s), stamp_s);
  while (!stamps_.empty() && stamps_.front() < stamps_.back() - horizon_s_) stamps_.pop_front();
}

double OdometryTimeline::gapAround(double stamp_s) const {
  const auto after = std::upper_bound(stamps_.begin(), stamps_.end(), stamp_s);
  if (after == stamps_.begin()) return std::numeric_limits<double>::infinity();
  const double before = *std::prev(after);
  if (before == stamp_s) return 0.0;
  // None after yet (a live node may see the frame before the sample that closes the gap): the
  // gap is at least this long.
  if (after == stamps_.end()) return stamp_s - before;
  return *after - before;
}

FrameDrop FrameGate::admit(double stamp_s, double newest_s) {
  if (have_last_ && stamp_s <= last_s_) return FrameDrop::kOutOfOrder;
  if (newest_s - stamp_s > config_.max_frame_age_s) return FrameDrop::kStale;
  have_last_ = true;
  last_s_ = stamp_s;
  return FrameDrop::kNone;
}

FrameDrop FrameGate::checkOdometry(double stamp_s, const OdometryTimeline& odometry) const {
  // No sample before the frame (odometry starting, or the timeline just reset): nothing to judge;
  // the pose look-up decides.
  if (!odometry.hasSampleBefore(stamp_s)) return FrameDrop::kNone;
  return odometry.gapAround(stamp_s) > config_.max_odometry_gap_s ? FrameDrop::kOdometryGap
                                                                  : FrameDrop::kNone;
}

}  // namespace geofusion
