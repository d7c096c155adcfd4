// The path from a synchronised depth image, camera_info and DetectionArray (with the odometry
// camera pose from TF) to the scene estimator: frame admission (order, age, odometry gaps),
// depth conversion, keyframe selection, detection checks and cap, the keyframe time budget. One
// code path for the estimator nodelet and the offline runner, so the same input gets the same
// decision; only their I/O (subscribers and TF, or a bag) differs.
#pragma once

#include "geofusion/background/background_worker.h"
#include "geofusion/common/ingestion.h"
#include "geofusion/estimation/frame_by_frame.h"
#include "geofusion/estimation/keyframe_selector.h"
#include "geofusion/estimation/map_store.h"
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/ros/conversions.h"

#include <geofusion/DetectionArray.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <memory>
#include <string>
#include <vector>

namespace geofusion {

class EstimatorPipeline {
 public:
  enum class Outcome { kKeyframe, kNotKeyframe, kDropped };

  /// The camera pose of a frame in the odometry frame, or why there is none.
  struct CameraPose {
    bool found = false;
    Eigen::Isometry3d T_odom_cam = Eigen::Isometry3d::Identity();
    std::string error;  ///< when not found
  };

  /// `background` non-null: every keyframe's depth, minus the map's objects, also goes into a
  /// background OctoMap, in a thread of its own when background->threaded (BackgroundWorker).
  /// Every model's render meshes are uploaded here, so the first keyframe does not wait.
  EstimatorPipeline(const ModelSet& models, const EstimatorConfig& estimator,
                    const KeyframeSelectorConfig& keyframes,
                    const FrameByFrame::Config& checks = FrameByFrame::Config(),
                    const BackgroundMapConfig* background = nullptr,
                    const IngestionConfig& ingestion = IngestionConfig());

  /// One synchronised frame with its odometry camera pose, when the newest input stamp seen is
  /// `newest_stamp_s`. A keyframe fills `result`; a dropped frame is counted (lastDrop()).
  Outcome process(const sensor_msgs::Image& depth, const sensor_msgs::CameraInfo& info,
                  const geofusion::DetectionArray& detections, const CameraPose& pose,
                  double newest_stamp_s, KeyframeResult* result);

  /// The odometry samples' stamps (odom -> base in TF, or odometry messages): the callers add
  /// them as they arrive; process() drops frames in a gap of them.
  OdometryTimeline& odometry() { return odometry_; }

  /// Frames that never made a synchronised set (the synchroniser's drops, unsynchronisedFrames),
  /// set by the caller that owns the synchroniser.
  void setUnsynchronised(std::size_t frames) {
    drops_.count[static_cast<std::size_t>(FrameDrop::kUnsynchronised)] = frames;
  }

  /// Frames lost before process() (the node's frame queue overflowing): counted as seen and
  /// dropped for `reason`.
  void countDropped(FrameDrop reason, std::size_t n) {
    frames_seen_ += n;
    drops_.add(reason, n);
  }

  FrameDrop lastDrop() const { return last_drop_; }
  /// Why the last frame had no camera pose (FrameDrop::kNoOdometry).
  const std::string& lastPoseError() const { return last_pose_error_; }
  /// Why the last frame's camera_info was unusable (FrameDrop::kBadCameraInfo).
  const std::string& lastCameraError() const { return last_camera_error_; }
  /// Frames given to process(), and those dropped by reason.
  std::size_t framesSeen() const { return frames_seen_; }
  const FrameDropCounts& drops() const { return drops_; }
  /// Keyframes over the time budget (input.keyframe_budget_ms: the estimator's time, and the
  /// background's when it runs in the estimator's thread), and whether the last one was.
  std::size_t budgetOverruns() const { return budget_overruns_; }
  bool lastKeyframeOverran() const { return last_overran_; }
  /// The last keyframe's time in the caller's thread (what the budget is compared with).
  double lastKeyframeMs() const { return last_keyframe_ms_; }
  /// Detections the cap dropped in the last frame (input.max_detections_per_frame).
  std::size_t lastCapped() const { return last_capped_; }
  const IngestionConfig& ingestionConfig() const { return gate_.config(); }

  SceneEstimator& estimator() { return *estimator_; }
  const SceneEstimator& estimator() const { return *estimator_; }
  /// The pinhole intrinsics of the last camera_info used (the BOP results' view test).
  const PinholeIntrinsics& intrinsics() const { return camera_.K(); }
  /// The background map's worker, or null when the pipeline has none.
  BackgroundWorker* background() { return background_.get(); }
  const DetectionTally& tally() const { return tally_; }  ///< detections used and skipped
  void reset();

  /// The map as it stands, ready for saveMap (map_store.h): the final solve's objects and
  /// contacts, the trajectory, the support plane, map -> odom, and the frames and detections
  /// used and dropped by reason. `final_solve` false: the objects and contacts as the last
  /// keyframe left them, without a last stage I and II (an autosave, cheap on the frame thread).
  RunResults currentMap(bool final_solve = true);
  /// Saves currentMap() and the background as one unit under `prefix`.
  bool saveMap(const std::string& prefix, RunResults map, MapFiles* files, std::string* error);
  /// Starts over from the map saved under `path` (map_store.h's loadMap): the estimator resumes
  /// its objects, the background its voxels. Fails, changing nothing, when the files cannot be
  /// read or do not belong together; whatever was mapped before is dropped on success.
  bool loadMap(const std::string& path, const ModelSet& models, RunResults* loaded,
               std::string* error);

 private:
  std::unique_ptr<SceneEstimator> estimator_;
  std::unique_ptr<BackgroundWorker> background_;
  Outcome drop(FrameDrop reason);
  void runKeyframe(const Keyframe& kf, KeyframeResult* result);

  KeyframeSelector selector_;
  FrameByFrame checker_;
  FrameGate gate_;
  OdometryTimeline odometry_;
  DetectionTally tally_;
  FrameDropCounts drops_;
  FrameDrop last_drop_ = FrameDrop::kNone;
  std::string last_pose_error_, last_camera_error_;
  std::size_t frames_seen_ = 0, budget_overruns_ = 0, last_capped_ = 0;
  bool last_overran_ = false;
  double last_keyframe_ms_ = 0.0;
  RunResults resumed_;  ///< the map loadMap() resumed, until the first keyframe after it
  std::vector<float> depth_;
  CameraRectifier camera_;  ///< K and the lens of camera_info; raw depth made pinhole
};

}  // namespace geofusion
