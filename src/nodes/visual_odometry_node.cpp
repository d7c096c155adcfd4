// Plain-node entry point of the RGB-D visual odometry (nodelet:
// geofusion/VisualOdometryNodelet).
#include "geofusion/ros/visual_odometry_node.h"
#include "geofusion/ros/node_main.h"

int main(int argc, char** argv) {
  return geofusion::runNode<geofusion::VisualOdometryNode>(argc, argv, "visual_odometry");
}
