// The path from a synchronised depth image, camera_info and DetectionArray (with the odometry
// camera pose from TF) to the scene estimator: keyframe selection, depth conversion, detection
// checks. One code path for the estimator nodelet and the offline runner; only their I/O
// differs.
#pragma once

#include "geofusion/background/background_map.h"
#include "geofusion/estimation/frame_by_frame.h"
#include "geofusion/estimation/keyframe_selector.h"
#include "geofusion/estimation/scene_estimator.h"

#include <geofusion/DetectionArray.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <memory>
#include <string>
#include <vector>

namespace geofusion {

class EstimatorPipeline {
 public:
  enum class Outcome { kKeyframe, kNotKeyframe, kBadDepth };

  /// `background` non-null: every keyframe's depth, minus the map's objects, also goes into a
  /// background OctoMap.
  EstimatorPipeline(const ModelSet& models, const EstimatorConfig& estimator,
                    const KeyframeSelectorConfig& keyframes,
                    const FrameByFrame::Config& checks = FrameByFrame::Config(),
                    const BackgroundMapConfig* background = nullptr);

  /// One synchronised frame with its odometry camera pose. A keyframe fills `result`.
  Outcome process(const sensor_msgs::Image& depth, const sensor_msgs::CameraInfo& info,
                  const geofusion::DetectionArray& detections, const Eigen::Isometry3d& T_odom_cam,
                  KeyframeResult* result);

  SceneEstimator& estimator() { return *estimator_; }
  /// The background map, or null when the pipeline has none.
  BackgroundMap* background() { return background_.get(); }
  double lastBackgroundMs() const { return background_ms_; }
  const DetectionTally& tally() const { return tally_; }  ///< detections used and skipped
  void reset();

 private:
  std::unique_ptr<SceneEstimator> estimator_;
  std::unique_ptr<BackgroundMap> background_;
  double background_ms_ = 0.0;
  KeyframeSelector selector_;
  FrameByFrame checker_;
  DetectionTally tally_;
  std::vector<float> depth_;
};

}  // namespace geofusion
