// The decisions on each incoming frame that the estimator node and run_offline must take alike:
// whether a synchronised frame is used or dropped, and why. ROS-free; times are stamps in
// seconds. The node and run_offline feed it the same facts (the frame's stamp, the newest stamp
// seen, the odometry samples around it) and report its counts: one input, one decision, wherever
// it runs.
#pragma once

#include <array>
#include <cstddef>
#include <deque>
#include <string>
#include <utility>
#include <vector>

namespace geofusion {

/// Why a synchronised frame (depth, camera_info, detections) was not used.
enum class FrameDrop {
  kNone = 0,
  kOutOfOrder,      ///< older than a frame already used (detections arriving late)
  kStale,           ///< older than the newest input by more than max_frame_age_s
  kUnsynchronised,  ///< a part never arrived with the others (run_offline; the node's synchroniser)
  kNoOdometry,      ///< no camera pose for its stamp (no TF, no odometry message)
  kOdometryGap,     ///< odometry samples around its stamp further apart than max_odometry_gap_s
  kBadDepth,        ///< empty, wrong encoding, or not the size camera_info says
  kBadCameraInfo,   ///< camera_info's K not a camera, or a lens distortion it cannot rectify
  kQueueOverflow,   ///< pushed out of the node's frame queue by newer frames
                    ///< (input.frame_queue_size)
  kCount
};

const char* toString(FrameDrop reason);

struct IngestionConfig {
  /// A frame whose odometry samples before and after are further apart than this is dropped
  /// instead of guessing its pose across the gap, s.
  double max_odometry_gap_s = 0.5;
  /// A frame older than the newest input stamp by more than this is dropped (processing lags,
  /// or a part arrived very late), s.
  double max_frame_age_s = 2.0;
  /// A keyframe taking longer than this is an overrun: counted, diagnostics WARN, ms.
  double keyframe_budget_ms = 200.0;
};

/// The nonzero counts of a table indexed by a reason enum, with the reasons' words (toString of
/// the enum): what the summaries print and the results files list.
template <typename Reason, std::size_t N>
std::vector<std::pair<std::string, std::size_t>> countsByReason(
    const std::array<std::size_t, N>& counts) {
  std::vector<std::pair<std::string, std::size_t>> out;
  for (std::size_t i = 0; i < N; ++i)
    if (counts[i] > 0) out.emplace_back(toString(static_cast<Reason>(i)), counts[i]);
  return out;
}

/// "2 out of order, 1 odometry gap": countsByReason as one line.
std::string reasonsLine(const std::vector<std::pair<std::string, std::size_t>>& counts);

/// Frames dropped, by reason.
struct FrameDropCounts {
  std::array<std::size_t, static_cast<std::size_t>(FrameDrop::kCount)> count{};

  void add(FrameDrop reason, std::size_t n = 1) { count[static_cast<std::size_t>(reason)] += n; }
  std::size_t of(FrameDrop reason) const { return count[static_cast<std::size_t>(reason)]; }
  std::size_t total() const;
  /// e.g. "3 dropped (2 out of order, 1 odometry gap)"; "none dropped".
  std::string summary() const;
};

/// Frames that never made a synchronised set: the most frequent input's message count minus the
/// sets made (what a synchroniser dropped), given each input's count.
std::size_t unsynchronisedFrames(const std::vector<std::size_t>& message_counts,
                                 std::size_t synchronised_sets);

/// The stamps of the odometry samples of the recent past (odom -> base transforms or odometry
/// messages), to tell a pose interpolated between close samples from one guessed across a gap.
class OdometryTimeline {
 public:
  /// Samples older than the newest by more than `horizon_s` are forgotten (bounded memory); a
  /// sample older than the newest by more than `jump_back_s` means time jumped back (a looping
  /// bag, a restarted driver): the timeline starts over from it. Seconds.
  explicit OdometryTimeline(double horizon_s = 120.0, double jump_back_s = 1.0)
      : horizon_s_(horizon_s), jump_back_s_(jump_back_s) {}

  void add(double stamp_s);
  void clear() { stamps_.clear(); }
  bool empty() const { return stamps_.empty(); }
  std::size_t size() const { return stamps_.size(); }

  bool hasSampleBefore(double stamp_s) const {
    return !stamps_.empty() && stamps_.front() <= stamp_s;
  }
  bool hasSampleAfter(double stamp_s) const { return !stamps_.empty() && stamps_.back() > stamp_s; }

  /// The time between the last sample at or before `stamp_s` and the first after it; 0 when a
  /// sample has this very stamp; with none after yet, the time since the last one; infinity
  /// with none before.
  double gapAround(double stamp_s) const;

 private:
  double horizon_s_, jump_back_s_;
  std::deque<double> stamps_;  ///< sorted
};

/// Admits the frames in stamp order: the first check of the shared ingestion path.
class FrameGate {
 public:
  explicit FrameGate(const IngestionConfig& config = IngestionConfig()) : config_(config) {}

  void setConfig(const IngestionConfig& config) { config_ = config; }
  const IngestionConfig& config() const { return config_; }

  /// kNone when a frame stamped `stamp_s` may be used when the newest input stamp is `newest_s`;
  /// else why not. Out-of-order is judged against the frames admitted before.
  FrameDrop admit(double stamp_s, double newest_s);
  /// kNone when the odometry around `stamp_s` is dense enough (no sample before it: not judged).
  FrameDrop checkOdometry(double stamp_s, const OdometryTimeline& odometry) const;

  /// After a time jump (a looping bag, a reset): anything goes again.
  void reset() { have_last_ = false; }

 private:
  IngestionConfig config_;
  bool have_last_ = false;
  double last_s_ = 0.0;
};

}  // namespace geofusion
