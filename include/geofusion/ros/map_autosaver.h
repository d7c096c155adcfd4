// The map saved on its own every N keyframes or T seconds (issue 52), so that a crash of the
// nodelet manager loses at most that much: the frame thread hands over a snapshot of the map
// (EstimatorPipeline::currentMap(false), no solve) and a thread of its own writes it with the
// same atomic, fsynced save as ~save_map (map_store.h), so the frame thread never waits for the
// disk. A newer snapshot replaces one still waiting. A failed save (a full disk, an unwritable
// folder) is counted and kept as the last error for the diagnostics; the previous autosave stays
// whole (map_store's guarantee) and mapping goes on. ROS-free: the node calls it.
#pragma once

#include "geofusion/estimation/map_store.h"
#include "geofusion/estimation/run_results.h"

#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace geofusion {

/// Whether the autosave under `prefix` is to be continued at start: only when the launch that
/// wrote it is this one (`launch_id`, the same for a respawned node and new for every roslaunch;
/// empty: never), so that a stale autosave of an earlier mapping run is never taken for this one.
enum class AutosaveResume { kNone, kResume, kOtherLaunch, kUnreadable };
AutosaveResume autosaveResume(const std::string& prefix, const std::string& launch_id,
                              std::string* session, std::string* error);

class MapAutosaver {
 public:
  struct Config {
    int every_keyframes = 10;  ///< a save after this many keyframes (0: not by count)
    double every_s = 60.0;     ///< ... or this long after the last (0: not by time)
    std::string prefix;        ///< where (map_store's prefix)
    bool enabled() const { return every_keyframes > 0 || every_s > 0.0; }
  };
  /// How a snapshot is saved (the pipeline's saveMap: the background too).
  using Save = std::function<bool(const std::string& prefix, RunResults map, MapFiles* files,
                                  std::string* error)>;
  struct Status {
    std::size_t saved = 0, failed = 0;  ///< saves done and failed since the start
    std::string last_error;             ///< of the last save, empty when it succeeded
    int last_keyframes = 0;             ///< keyframes_total of the last successful save
    double last_saved_s = -1.0;         ///< when (the clock given to keyframeAdded), -1: never
    bool pending = false;               ///< a snapshot waits for the writer
  };

  MapAutosaver(const Config& config, Save save);
  /// Writes a snapshot still waiting, then stops the writer.
  ~MapAutosaver();
  MapAutosaver(const MapAutosaver&) = delete;
  MapAutosaver& operator=(const MapAutosaver&) = delete;

  bool enabled() const { return config_.enabled(); }
  const Config& config() const { return config_; }
  /// A keyframe was added at `now_s`: true when a save is due (the count reached, or the time
  /// since the last save passed); the caller then offers a snapshot.
  bool keyframeAdded(double now_s);
  /// Hands a snapshot to the writer (replacing one still waiting) and restarts the count.
  void offer(RunResults map, double now_s);
  /// Waits until the writer has nothing left (tests, shutdown).
  void flush();
  Status status() const;

 private:
  void run();

  const Config config_;
  const Save save_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::unique_ptr<RunResults> pending_;
  bool writing_ = false, stop_ = false;
  int keyframes_since_ = 0;
  double last_offer_s_ = -1.0;
  double pending_s_ = -1.0;
  Status status_;
  std::thread writer_;
};

}  // namespace geofusion
