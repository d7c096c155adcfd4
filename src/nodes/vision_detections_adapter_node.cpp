// Plain-node entry point of the vision_msgs adapter (nodelet: geofusion/VisionDetectionsAdapter).
#include "geofusion/ros/node_main.h"
#include "geofusion/ros/vision_detections_adapter.h"

int main(int argc, char** argv) {
  return geofusion::runNode<geofusion::VisionDetectionsAdapter>(argc, argv,
                                                                "vision_detections_adapter");
}
