#include "geofusion/estimation/refinement_pool.h"

#include "geofusion/render/renderer.h"

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>

namespace geofusion {

struct RefinementPool::Impl {
  std::vector<std::thread> threads;
  std::mutex mutex;
  std::condition_variable start, done;
  int ready = 0, busy = 0;
  unsigned generation = 0;
  bool stop = false;
  // The batch under way (valid while busy > 0 or the caller works).
  ConsistencyConfig consistency;
  DepthRefinementConfig refinement;
  const std::vector<RefinementJob>* jobs = nullptr;
  DepthImageView depth;
  PinholeIntrinsics K;
  std::vector<DepthRefinement>* out = nullptr;
  std::atomic<std::size_t> next{0};

  // Takes jobs until none is left.
  void work(DepthRefiner* refiner) {
    for (std::size_t i = next++; i < jobs->size(); i = next++) {
      const RefinementJob& job = (*jobs)[i];
      (*out)[i] = refiner->refine(job.model, job.T_cam_obj, depth, K);
    }
  }

  void run(const std::vector<std::shared_ptr<const ObjectModel>>& models) {
    std::unique_lock<std::mutex> lock(mutex);
    ConsistencyScorer scorer(std::make_shared<OffscreenRenderer>(), consistency);
    DepthRefiner refiner(&scorer, refinement);
    lock.unlock();
    for (const auto& model : models) scorer.prepare(model);
    lock.lock();
    ++ready;
    done.notify_all();
    unsigned seen = generation;
    while (true) {
      start.wait(lock, [&] { return stop || generation != seen; });
      if (stop) return;
      seen = generation;
      scorer.setConfig(consistency);
      refiner.setConfig(refinement);
      lock.unlock();
      work(&refiner);
      lock.lock();
      if (--busy == 0) done.notify_all();
    }
  }
};

RefinementPool::RefinementPool(int workers, const ConsistencyConfig& consistency,
                               const DepthRefinementConfig& refinement,
                               const std::vector<std::shared_ptr<const ObjectModel>>& models)
    : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.consistency = consistency;
  d.refinement = refinement;
  for (int i = 0; i < workers; ++i) d.threads.emplace_back([&d, models] { d.run(models); });
  std::unique_lock<std::mutex> lock(d.mutex);
  d.done.wait(lock, [&] { return d.ready == workers; });  // every model uploaded: no first stall
}

RefinementPool::~RefinementPool() {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->stop = true;
  }
  impl_->start.notify_all();
  for (std::thread& t : impl_->threads) t.join();
}

void RefinementPool::setConfig(const ConsistencyConfig& consistency,
                               const DepthRefinementConfig& refinement) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->consistency = consistency;
  impl_->refinement = refinement;
}

int RefinementPool::workers() const {
  return static_cast<int>(impl_->threads.size());
}

std::vector<DepthRefinement> RefinementPool::refine(const std::vector<RefinementJob>& jobs,
                                                    const DepthImageView& depth,
                                                    const PinholeIntrinsics& K,
                                                    DepthRefiner* caller) {
  Impl& d = *impl_;
  std::vector<DepthRefinement> out(jobs.size());
  bool parallel = false;
  {
    std::lock_guard<std::mutex> lock(d.mutex);
    d.jobs = &jobs;
    d.depth = depth;
    d.K = K;
    d.out = &out;
    d.next = 0;
    d.busy = jobs.size() > 1 ? static_cast<int>(d.threads.size()) : 0;
    parallel = d.busy > 0;
    if (parallel) ++d.generation;
  }
  if (parallel) d.start.notify_all();
  d.work(caller);
  std::unique_lock<std::mutex> lock(d.mutex);
  d.done.wait(lock, [&] { return d.busy == 0; });
  d.jobs = nullptr;
  d.out = nullptr;
  return out;
}

}  // namespace geofusion
