#include "geofusion/ros/estimator_pipeline.h"

#include "geofusion/render/renderer.h"
#include "geofusion/ros/conversions.h"

#include <chrono>

namespace geofusion {

EstimatorPipeline::EstimatorPipeline(const ModelSet& models, const EstimatorConfig& estimator,
                                     const KeyframeSelectorConfig& keyframes,
                                     const FrameByFrame::Config& checks,
                                     const BackgroundMapConfig* background,
                                     const IngestionConfig& ingestion)
    : selector_(keyframes), checker_(checks), gate_(ingestion) {
  estimator_ = std::make_unique<SceneEstimator>(models, estimator);
  estimator_->prepare();
  if (background) background_ = std::make_unique<BackgroundWorker>(*background, &models);
  std::set<std::string> classes;
  for (const auto& model : models.models()) classes.insert(model->name);
  checker_.setKnownClasses(std::move(classes));
}

void EstimatorPipeline::reset() {
  estimator_->reset();
  selector_.reset();
  gate_.reset();
  odometry_.clear();
  if (background_) background_->clear();
  tally_ = DetectionTally();
  drops_ = FrameDropCounts();
  frames_seen_ = budget_overruns_ = last_capped_ = 0;
  last_drop_ = FrameDrop::kNone;
  last_overran_ = false;
  resumed_ = RunResults();
}

RunResults EstimatorPipeline::currentMap(bool final_solve) {
  RunResults map;
  const bool mapped = estimator_->numKeyframes() > 0;
  map.final_map = !mapped       ? resumed_.final_map
                  : final_solve ? estimator_->finish()
                                : estimator_->snapshot();
  map.keyframes_total = resumed_.keyframes_total + estimator_->numKeyframes();
  map.next_object_id = estimator_->nextObjectId();
  map.trajectory = estimator_->trajectory();
  map.trajectory_stamps = estimator_->keyframeStamps();
  map.support_plane = estimator_->supportPlane();
  map.T_map_odom = estimator_->numKeyframes() > 0 ? estimator_->T_map_odom() : resumed_.T_map_odom;
  map.frames_seen = static_cast<int>(frames_seen_);
  // Of the synchronised frames; those that never made a set are in frames_dropped only.
  map.frames_skipped = static_cast<int>(drops_.total() - drops_.of(FrameDrop::kUnsynchronised));
  map.frames_dropped = countsByReason<FrameDrop>(drops_.count);
  map.detections_dropped = countsByReason<SkipReason>(tally_.skipped);
  map.keyframes_over_budget = static_cast<int>(budget_overruns_);
  return map;
}

bool EstimatorPipeline::saveMap(const std::string& prefix, RunResults map, MapFiles* files,
                                std::string* error) {
  BackgroundWriter write_background;
  if (background_) {
    write_background = [this](const std::string& path, std::string* e) {
      bool written = false;
      background_->withMap([&](BackgroundMap& map) { written = map.writeBinary(path, e); });
      return written;
    };
  }
  return geofusion::saveMap(prefix, std::move(map), write_background, files, error);
}

bool EstimatorPipeline::loadMap(const std::string& path, const ModelSet& models, RunResults* loaded,
                                std::string* error) {
  RunResults map;
  MapFiles files;
  if (!geofusion::loadMap(path, models, &map, &files, error)) return false;
  reset();  // the pieces were checked to belong together
  bool read = true;
  if (background_ && !files.background.empty()) {
    background_->withMap(
        [&](BackgroundMap& map) { read = map.readBinary(files.background, error); });
  }
  if (!read) return false;
  estimator_->resume(map.final_map.objects, map.T_map_odom, map.next_object_id, &map.support_plane);
  resumed_ = map;
  if (loaded) *loaded = std::move(map);
  return true;
}

EstimatorPipeline::Outcome EstimatorPipeline::drop(FrameDrop reason) {
  last_drop_ = reason;
  drops_.add(reason);
  return Outcome::kDropped;
}

EstimatorPipeline::Outcome EstimatorPipeline::process(const sensor_msgs::Image& depth,
                                                      const sensor_msgs::CameraInfo& info,
                                                      const geofusion::DetectionArray& detections,
                                                      const CameraPose& pose, double newest_stamp_s,
                                                      KeyframeResult* result) {
  ++frames_seen_;
  last_drop_ = FrameDrop::kNone;
  last_capped_ = 0;
  const double stamp_s = detections.header.stamp.toSec();
  if (const FrameDrop order = gate_.admit(stamp_s, newest_stamp_s); order != FrameDrop::kNone)
    return drop(order);
  // A frame in a gap of the odometry is dropped as such, whether its pose could be interpolated
  // across the gap (a recording read whole) or not yet (live, the samples after it not arrived).
  if (const FrameDrop gap = gate_.checkOdometry(stamp_s, odometry_); gap != FrameDrop::kNone)
    return drop(gap);
  if (!pose.found) {
    // Odometry that stopped before the frame (samples before it, none after) is a gap too.
    last_pose_error_ = pose.error;
    return drop(odometry_.hasSampleBefore(stamp_s) && !odometry_.hasSampleAfter(stamp_s)
                    ? FrameDrop::kOdometryGap
                    : FrameDrop::kNoOdometry);
  }
  if (!camera_.update(info, &last_camera_error_)) return drop(FrameDrop::kBadCameraInfo);
  const PinholeIntrinsics& K = camera_.K();
  if (!depthToMetres(depth, &depth_) ||
      depth_.size() != static_cast<std::size_t>(K.width) * K.height) {
    return drop(FrameDrop::kBadDepth);
  }
  if (!selector_.select(pose.T_odom_cam)) return Outcome::kNotKeyframe;
  // A distorted camera's depth made pinhole (sizes checked above; OpenCV failing is reported).
  if (!camera_.rectifyDepth(&depth_)) {
    last_camera_error_ = "the depth could not be rectified with camera_info's distortion";
    return drop(FrameDrop::kBadCameraInfo);
  }
  Keyframe kf;
  kf.stamp_s = stamp_s;
  kf.K = K;
  kf.T_odom_cam = pose.T_odom_cam;
  kf.depth = DepthImageView{depth_.data(), K.width, K.height};
  const std::size_t capped_before = tally_.skipped[static_cast<std::size_t>(SkipReason::kOverCap)];
  for (const WorldDetection& d : checker_.process(fromMsg(detections), pose.T_odom_cam, &tally_))
    kf.detections.push_back(d.measurement);
  last_capped_ = tally_.skipped[static_cast<std::size_t>(SkipReason::kOverCap)] - capped_before;
  runKeyframe(kf, result);
  return Outcome::kKeyframe;
}

// The estimator's keyframe, then the background's (in its own thread, or in this one), and the
// time budget of what ran here.
void EstimatorPipeline::runKeyframe(const Keyframe& kf, KeyframeResult* result) {
  *result = estimator_->addKeyframe(kf);
  double background_ms = 0.0;
  if (background_) {
    std::vector<MaskObject> objects;
    for (const ObjectEstimate& o : result->objects) objects.push_back({o.model, o.T_map_obj});
    background_->submit(kf.depth, kf.K, result->T_map_cam, std::move(objects), kf.stamp_s);
    if (!background_->config().threaded) background_ms = background_->stats().last_ms;
  }
  last_keyframe_ms_ = result->timings.total_ms + background_ms;
  last_overran_ = last_keyframe_ms_ > gate_.config().keyframe_budget_ms;
  budget_overruns_ += last_overran_;
}

}  // namespace geofusion
