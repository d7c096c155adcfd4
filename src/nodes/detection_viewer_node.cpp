// Plain-node entry point of the frame-by-frame detection viewer (nodelet:
// geofusion/DetectionViewerNodelet).
#include "geofusion/ros/detection_viewer.h"
#include "geofusion/ros/node_main.h"

int main(int argc, char** argv) {
  return geofusion::runNode<geofusion::DetectionViewer>(argc, argv, "detection_viewer");
}
