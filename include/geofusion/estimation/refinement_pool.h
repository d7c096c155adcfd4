#pragma once
// Detections refined and scored by several threads at once (consistency.threads): each worker
// owns an OSMesa renderer, its scorer and its refiner, all made in the worker's own thread (an
// OSMesa context stays in one thread) with every model uploaded at start; the caller's refiner
// takes its share of the jobs too. A detection's result depends on its inputs only, so the
// results are those of one thread, whichever thread computed each.

#include "geofusion/common/camera.h"
#include "geofusion/common/images.h"
#include "geofusion/estimation/depth_refinement.h"
#include "geofusion/model/object_model.h"
#include "geofusion/render/consistency.h"

#include <Eigen/Geometry>

#include <memory>
#include <vector>

namespace geofusion {

struct RefinementJob {
  std::shared_ptr<const ObjectModel> model;
  Eigen::Isometry3d T_cam_obj = Eigen::Isometry3d::Identity();
};

class RefinementPool {
 public:
  /// `workers` threads beside the caller's; `models` are uploaded to each worker's renderer
  /// before the constructor returns.
  RefinementPool(int workers, const ConsistencyConfig& consistency,
                 const DepthRefinementConfig& refinement,
                 const std::vector<std::shared_ptr<const ObjectModel>>& models);
  ~RefinementPool();
  RefinementPool(const RefinementPool&) = delete;
  RefinementPool& operator=(const RefinementPool&) = delete;

  /// The settings the next batch runs with (the workers take them at its start).
  void setConfig(const ConsistencyConfig& consistency, const DepthRefinementConfig& refinement);
  /// Every job refined and scored against `depth` (camera K), results in the jobs' order;
  /// `caller` (the estimator's own refiner, with the same settings) works through jobs too.
  std::vector<DepthRefinement> refine(const std::vector<RefinementJob>& jobs,
                                      const DepthImageView& depth, const PinholeIntrinsics& K,
                                      DepthRefiner* caller);
  int workers() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace geofusion
