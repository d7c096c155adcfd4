// The background map beside the estimator: keyframes are handed over (their depth copied) and
// inserted in a thread of its own with its own renderer, so the object map never waits for the
// OctoMap. At most one keyframe waits: a newer one replaces it (counted as skipped), so a slow
// background falls behind in what it has seen, never in time. With BackgroundMapConfig::threaded
// false (or wait set) every keyframe is inserted before submit() returns.
#pragma once

#include "geofusion/background/background_map.h"
#include "geofusion/common/statistics.h"

#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace geofusion {

class BackgroundWorker {
 public:
  /// Called on the worker's thread after each insertion, with the map (not to be kept), the
  /// keyframe's stamp and the number of insertions so far.
  using Listener = std::function<void(const BackgroundMap&, double stamp_s, std::size_t inserted)>;

  /// `models` non-null: their mask meshes are uploaded here, not at the first keyframe.
  explicit BackgroundWorker(const BackgroundMapConfig& config, const ModelSet* models = nullptr);
  ~BackgroundWorker();
  BackgroundWorker(const BackgroundWorker&) = delete;
  BackgroundWorker& operator=(const BackgroundWorker&) = delete;

  /// Hands a keyframe over (the depth is copied). Threaded: returns at once; otherwise, or with
  /// setWait(true), after its insertion.
  void submit(const DepthImageView& depth, const PinholeIntrinsics& K,
              const Eigen::Isometry3d& T_map_cam, std::vector<MaskObject> objects, double stamp_s);
  /// Every keyframe submitted is inserted (or skipped) before submit() returns: repeatable runs.
  void setWait(bool wait) { wait_ = wait; }
  void waitIdle();
  void setListener(Listener listener);

  BackgroundStats stats() const;
  /// Runs `f` on the map while no insertion runs (the map's readers: publishing, saving).
  void withMap(const std::function<void(BackgroundMap&)>& f);
  /// Drops the map and any keyframe waiting; the statistics start again.
  void clear();
  const BackgroundMapConfig& config() const { return config_; }

 private:
  struct Job {
    std::vector<float> depth;
    PinholeIntrinsics K;
    Eigen::Isometry3d T_map_cam = Eigen::Isometry3d::Identity();
    std::vector<MaskObject> objects;
    double stamp_s = 0.0;
  };
  void run();
  void insert(const Job& job);

  BackgroundMapConfig config_;
  std::unique_ptr<BackgroundMap> map_;
  /// The map, the listener and the insertion figures; never taken by submit(). Order: map_mutex_
  /// before queue_mutex_ where both are held.
  mutable std::mutex map_mutex_;
  std::vector<double> times_ms_;
  BackgroundStats stats_;
  Listener listener_;

  mutable std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::unique_ptr<Job> pending_;
  std::size_t submitted_ = 0, skipped_ = 0;
  bool busy_ = false, stop_ = false, wait_ = false;
  std::thread thread_;
};

}  // namespace geofusion
