// Plain-node entry point of the frame-by-frame detection viewer.
#include "geofusion/ros/detection_viewer.h"

#include <ros/ros.h>

#include <exception>

int main(int argc, char** argv) {
  ros::init(argc, argv, "detection_viewer");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  try {
    geofusion::DetectionViewer viewer(nh, pnh);
    ros::spin();
  } catch (const std::exception& e) {  // a bad configuration: refuse to start, say why
    ROS_FATAL_STREAM("geofusion: " << e.what());
    return 1;
  }
  return 0;
}
