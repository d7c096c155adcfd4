// The RGB-D visual odometry as a plain node (the nodelet is geofusion/VisualOdometryNodelet).
#include "geofusion/ros/visual_odometry_node.h"

#include <ros/ros.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "visual_odometry");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  geofusion::VisualOdometryNode node(nh, pnh);
  ros::spin();
  return 0;
}
