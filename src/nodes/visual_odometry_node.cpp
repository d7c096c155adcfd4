// The RGB-D visual odometry as a plain node (the nodelet is geofusion/VisualOdometryNodelet).
#include "geofusion/ros/visual_odometry_node.h"

#include <ros/ros.h>

#include <exception>

int main(int argc, char** argv) {
  ros::init(argc, argv, "visual_odometry");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  try {
    geofusion::VisualOdometryNode node(nh, pnh);
    ros::spin();
  } catch (const std::exception& e) {  // a bad configuration: refuse to start, say why
    ROS_FATAL_STREAM("geofusion: " << e.what());
    return 1;
  }
  return 0;
}
