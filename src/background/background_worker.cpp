#include "geofusion/background/background_worker.h"

#include "geofusion/common/statistics.h"
#include "geofusion/render/renderer.h"

#include <algorithm>
#include <ctime>

namespace geofusion {

BackgroundWorker::BackgroundWorker(const BackgroundMapConfig& config, const ModelSet* models)
    : config_(config),
      // Its own OSMesa context: the estimator's scores never wait for the background's masks.
      map_(std::make_unique<BackgroundMap>(config, std::make_shared<OffscreenRenderer>())) {
  if (models) map_->prepare(*models);
  if (config_.threaded) thread_ = std::thread([this] { run(); });
}

BackgroundWorker::~BackgroundWorker() {
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    stop_ = true;
  }
  queue_cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void BackgroundWorker::setListener(Listener listener) {
  std::lock_guard<std::mutex> lock(map_mutex_);
  listener_ = std::move(listener);
}

void BackgroundWorker::submit(const DepthImageView& depth, const PinholeIntrinsics& K,
                              const Eigen::Isometry3d& T_map_cam, std::vector<MaskObject> objects,
                              double stamp_s) {
  auto job = std::make_unique<Job>();
  if (depth.data)
    job->depth.assign(depth.data, depth.data + std::size_t(depth.width) * depth.height);
  job->K = K;
  job->T_map_cam = T_map_cam;
  job->objects = std::move(objects);
  job->stamp_s = stamp_s;
  {
    // Never map_mutex_ here: the caller must not wait for an insertion under way.
    std::lock_guard<std::mutex> lock(queue_mutex_);
    ++submitted_;
    if (thread_.joinable()) {
      skipped_ += pending_ != nullptr;
      pending_ = std::move(job);
    }
  }
  if (!thread_.joinable()) {
    insert(*job);
    return;
  }
  queue_cv_.notify_all();
  if (wait_) waitIdle();
}

void BackgroundWorker::waitIdle() {
  std::unique_lock<std::mutex> lock(queue_mutex_);
  queue_cv_.wait(lock, [this] { return (!pending_ && !busy_) || stop_; });
}

void BackgroundWorker::run() {
  for (;;) {
    std::unique_ptr<Job> job;
    {
      std::unique_lock<std::mutex> lock(queue_mutex_);
      queue_cv_.wait(lock, [this] { return pending_ || stop_; });
      if (stop_) return;
      job = std::move(pending_);
      busy_ = true;
    }
    insert(*job);
    {
      std::lock_guard<std::mutex> lock(queue_mutex_);
      busy_ = false;
    }
    queue_cv_.notify_all();
  }
}

void BackgroundWorker::insert(const Job& job) {
  std::lock_guard<std::mutex> lock(map_mutex_);
  const double start = threadCpuMs();
  if (!map_->wanted(job.T_map_cam)) {
    ++stats_.still;
    stats_.total_ms += threadCpuMs() - start;
    return;
  }
  map_->insert(DepthImageView{job.depth.data(), job.K.width, job.K.height}, job.K, job.T_map_cam,
               job.objects);
  const double ms = threadCpuMs() - start;
  times_ms_.push_back(ms);
  ++stats_.inserted;
  stats_.last_ms = ms;
  stats_.total_ms += ms;
  stats_.max_ms = std::max(stats_.max_ms, ms);
  if (listener_) listener_(*map_, job.stamp_s, stats_.inserted);
}

BackgroundStats BackgroundWorker::stats() const {
  std::lock_guard<std::mutex> lock(map_mutex_);
  BackgroundStats s = stats_;
  {
    std::lock_guard<std::mutex> queue_lock(queue_mutex_);
    s.submitted = submitted_;
    s.skipped = skipped_;
  }
  if (!times_ms_.empty()) {
    s.p50_ms = percentile(times_ms_, 0.5);
    s.p95_ms = percentile(times_ms_, 0.95);
  }
  return s;
}

void BackgroundWorker::withMap(const std::function<void(BackgroundMap&)>& f) {
  std::lock_guard<std::mutex> lock(map_mutex_);
  f(*map_);
}

void BackgroundWorker::clear() {
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    pending_.reset();
    submitted_ = skipped_ = 0;
  }
  waitIdle();
  std::lock_guard<std::mutex> lock(map_mutex_);
  map_->clear();
  times_ms_.clear();
  stats_ = BackgroundStats();
}

}  // namespace geofusion
