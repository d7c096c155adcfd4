// Plain-node entry point of the scene estimator.
#include "geofusion/ros/scene_estimator_node.h"

#include <ros/ros.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "scene_estimator");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  geofusion::SceneEstimatorNode node(nh, pnh);
  ros::spin();
  return 0;
}
