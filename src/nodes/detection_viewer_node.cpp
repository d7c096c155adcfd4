// Plain-node entry point of the frame-by-frame detection viewer.
#include "geofusion/ros/detection_viewer.h"

#include <ros/ros.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "detection_viewer");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  geofusion::DetectionViewer viewer(nh, pnh);
  ros::spin();
  return 0;
}
