#include "geofusion/ros/estimator_pipeline.h"

#include "geofusion/render/renderer.h"
#include "geofusion/ros/conversions.h"

#include <chrono>

namespace geofusion {

EstimatorPipeline::EstimatorPipeline(const ModelSet& models, const EstimatorConfig& estimator,
                                     const KeyframeSelectorConfig& keyframes,
                                     const FrameByFrame::Config& checks,
                                     const BackgroundMapConfig* background)
    : selector_(keyframes), checker_(checks) {
  // One OSMesa context for the consistency scores and the background's object masks.
  auto renderer = std::make_shared<OffscreenRenderer>();
  estimator_ = std::make_unique<SceneEstimator>(models, estimator, renderer);
  if (background) background_ = std::make_unique<BackgroundMap>(*background, renderer);
}

void EstimatorPipeline::reset() {
  estimator_->reset();
  selector_.reset();
  if (background_) background_->clear();
  tally_ = DetectionTally();
}

EstimatorPipeline::Outcome EstimatorPipeline::process(const sensor_msgs::Image& depth,
                                                      const sensor_msgs::CameraInfo& info,
                                                      const geofusion::DetectionArray& detections,
                                                      const Eigen::Isometry3d& T_odom_cam,
                                                      KeyframeResult* result) {
  const PinholeIntrinsics K = intrinsicsFromCameraInfo(info);
  if (!K.valid() || !depthToMetres(depth, &depth_) ||
      depth_.size() != static_cast<std::size_t>(K.width) * K.height) {
    return Outcome::kBadDepth;
  }
  if (!selector_.select(T_odom_cam)) return Outcome::kNotKeyframe;
  Keyframe kf;
  kf.stamp_s = detections.header.stamp.toSec();
  kf.K = K;
  kf.T_odom_cam = T_odom_cam;
  kf.depth = DepthImageView{depth_.data(), K.width, K.height};
  for (const WorldDetection& d : checker_.process(fromMsg(detections), T_odom_cam, &tally_)) {
    kf.detections.push_back(d.measurement);
  }
  *result = estimator_->addKeyframe(kf);
  if (background_) {
    const auto start = std::chrono::steady_clock::now();
    std::vector<MaskObject> objects;
    for (const ObjectEstimate& o : result->objects) objects.push_back({o.model, o.T_map_obj});
    background_->insert(kf.depth, K, result->T_map_cam, objects);
    background_ms_ =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  }
  return Outcome::kKeyframe;
}

}  // namespace geofusion
