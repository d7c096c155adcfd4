#include "geofusion/ros/map_autosaver.h"

#include <utility>

namespace geofusion {

AutosaveResume autosaveResume(const std::string& prefix, const std::string& launch_id,
                              std::string* session, std::string* error) {
  bool exists = false;
  if (!readSavedMapSession(prefix, session, &exists, error))
    return exists ? AutosaveResume::kUnreadable : AutosaveResume::kNone;
  return !launch_id.empty() && *session == launch_id ? AutosaveResume::kResume
                                                     : AutosaveResume::kOtherLaunch;
}

MapAutosaver::MapAutosaver(const Config& config, Save save)
    : config_(config), save_(std::move(save)) {
  if (enabled()) writer_ = std::thread([this] { run(); });
}

MapAutosaver::~MapAutosaver() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (writer_.joinable()) writer_.join();
}

bool MapAutosaver::keyframeAdded(double now_s) {
  if (!enabled()) return false;
  std::lock_guard<std::mutex> lock(mutex_);
  ++keyframes_since_;
  if (last_offer_s_ < 0.0) last_offer_s_ = now_s;  // the clock starts at the first keyframe
  const bool by_count = config_.every_keyframes > 0 && keyframes_since_ >= config_.every_keyframes;
  const bool by_time = config_.every_s > 0.0 && now_s - last_offer_s_ >= config_.every_s;
  return by_count || by_time;
}

void MapAutosaver::offer(RunResults map, double now_s) {
  if (!enabled()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_ = std::make_unique<RunResults>(std::move(map));
    pending_s_ = now_s;
    keyframes_since_ = 0;
    last_offer_s_ = now_s;
  }
  cv_.notify_all();
}

void MapAutosaver::flush() {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [this] { return (!pending_ && !writing_) || !writer_.joinable(); });
}

MapAutosaver::Status MapAutosaver::status() const {
  std::lock_guard<std::mutex> lock(mutex_);
  Status s = status_;
  s.pending = pending_ != nullptr || writing_;
  return s;
}

// The writer: one snapshot at a time, the newest; on stop, the one still waiting first.
void MapAutosaver::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    cv_.wait(lock, [this] { return stop_ || pending_; });
    if (!pending_) return;  // stopping, nothing left
    std::unique_ptr<RunResults> map = std::move(pending_);
    const double offered_s = pending_s_;
    writing_ = true;
    lock.unlock();
    MapFiles files;
    std::string error;
    const int keyframes = map->keyframes_total;
    const bool ok = save_(config_.prefix, std::move(*map), &files, &error);
    lock.lock();
    writing_ = false;
    if (ok) {
      ++status_.saved;
      status_.last_error.clear();
      status_.last_keyframes = keyframes;
      status_.last_saved_s = offered_s;
    } else {
      ++status_.failed;
      status_.last_error = error.empty() ? "the save failed without a reason" : error;
    }
    cv_.notify_all();
  }
}

}  // namespace geofusion
