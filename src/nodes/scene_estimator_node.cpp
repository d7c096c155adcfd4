// Plain-node entry point of the scene estimator (the nodelet is geofusion/SceneEstimatorNodelet).
#include "geofusion/ros/scene_estimator_node.h"
#include "geofusion/ros/node_main.h"

int main(int argc, char** argv) {
  return geofusion::runNode<geofusion::SceneEstimatorNode>(argc, argv, "scene_estimator");
}
