// Plain-node entry point of the scene estimator.
#include "geofusion/ros/scene_estimator_node.h"

#include <ros/ros.h>

#include <exception>

int main(int argc, char** argv) {
  ros::init(argc, argv, "scene_estimator");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  try {
    geofusion::SceneEstimatorNode node(nh, pnh);
    ros::spin();
  } catch (const std::exception& e) {  // a bad configuration: refuse to start, say why
    ROS_FATAL_STREAM("geofusion: " << e.what());
    return 1;
  }
  return 0;
}
