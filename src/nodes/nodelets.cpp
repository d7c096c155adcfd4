// Nodelet entry points: each constructs the node class from the nodelet's handles; a bad
// configuration (the constructor throws) leaves the nodelet stopped with a FATAL message.
#include "geofusion/ros/detection_viewer.h"
#include "geofusion/ros/scene_estimator_node.h"
#include "geofusion/ros/vision_detections_adapter.h"
#include "geofusion/ros/visual_odometry_node.h"

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include <exception>
#include <memory>

namespace geofusion {

// Constructs the node; on a bad configuration says why and leaves it unstarted.
template <class Node>
class NodeletOf : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      node_ = std::make_unique<Node>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const std::exception& e) {
      NODELET_FATAL_STREAM("geofusion: " << e.what());
    }
  }
  std::unique_ptr<Node> node_;
};

class DetectionViewerNodelet : public NodeletOf<DetectionViewer> {};
class SceneEstimatorNodelet : public NodeletOf<SceneEstimatorNode> {};
class VisualOdometryNodelet : public NodeletOf<VisualOdometryNode> {};
class VisionDetectionsAdapterNodelet : public NodeletOf<VisionDetectionsAdapter> {};

}  // namespace geofusion

PLUGINLIB_EXPORT_CLASS(geofusion::DetectionViewerNodelet, nodelet::Nodelet)
PLUGINLIB_EXPORT_CLASS(geofusion::SceneEstimatorNodelet, nodelet::Nodelet)
PLUGINLIB_EXPORT_CLASS(geofusion::VisualOdometryNodelet, nodelet::Nodelet)
PLUGINLIB_EXPORT_CLASS(geofusion::VisionDetectionsAdapterNodelet, nodelet::Nodelet)
