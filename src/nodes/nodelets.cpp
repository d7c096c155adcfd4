// Nodelet entry points: each only constructs the node class from the nodelet's handles.
#include "geofusion/ros/detection_viewer.h"
#include "geofusion/ros/scene_estimator_node.h"
#include "geofusion/ros/visual_odometry_node.h"

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include <memory>

namespace geofusion {

class DetectionViewerNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    viewer_ = std::make_unique<DetectionViewer>(getNodeHandle(), getPrivateNodeHandle());
  }
  std::unique_ptr<DetectionViewer> viewer_;
};

class SceneEstimatorNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    node_ = std::make_unique<SceneEstimatorNode>(getNodeHandle(), getPrivateNodeHandle());
  }
  std::unique_ptr<SceneEstimatorNode> node_;
};

class VisualOdometryNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    node_ = std::make_unique<VisualOdometryNode>(getNodeHandle(), getPrivateNodeHandle());
  }
  std::unique_ptr<VisualOdometryNode> node_;
};

}  // namespace geofusion

PLUGINLIB_EXPORT_CLASS(geofusion::DetectionViewerNodelet, nodelet::Nodelet)
PLUGINLIB_EXPORT_CLASS(geofusion::SceneEstimatorNodelet, nodelet::Nodelet)
PLUGINLIB_EXPORT_CLASS(geofusion::VisualOdometryNodelet, nodelet::Nodelet)
