// The vision_msgs adapter: vision_msgs/Detection3DArray (Noetic layout) on ~vision_detections_topic
// (default vision_detections) in, the package's DetectionArray on ~detections_topic (the robot
// file's, default detections) out, class ids mapped to the model set through
// vision_msgs.class_map. Subscribes without the vision_msgs package (topic_tools::ShapeShifter:
// the bytes, their type and MD5 sum). Run as a nodelet (geofusion/VisionDetectionsAdapter) or a
// node (vision_detections_adapter_node).
#pragma once

#include "geofusion/ros/vision_detections.h"

#include <ros/ros.h>
#include <topic_tools/shape_shifter.h>

#include <memory>
#include <mutex>
#include <string>

namespace geofusion {

class VisionDetectionsAdapter {
 public:
  VisionDetectionsAdapter(ros::NodeHandle nh, ros::NodeHandle pnh);
  ~VisionDetectionsAdapter();

 private:
  void onMessage(const topic_tools::ShapeShifter::ConstPtr& msg);

  ros::NodeHandle nh_;
  ros::NodeHandle pnh_;
  double warn_period_s_ = 5.0;
  std::mutex mutex_;
  std::unique_ptr<VisionDetectionConverter> converter_;
  std::string reported_;  // the dropped summary last warned about
  ros::Subscriber sub_;
  ros::Publisher pub_;
};

}  // namespace geofusion
