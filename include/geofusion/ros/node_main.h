// The plain-node entry point every node shares: ros::init, the node class built from the node's
// handles, spin. A bad configuration (the node's constructor throws) is said at FATAL and the
// process exits 1: the node refuses to start. The nodelets do the same in src/nodes/nodelets.cpp.
#pragma once

#include <ros/ros.h>

#include <exception>

namespace geofusion {

template <class Node>
int runNode(int argc, char** argv, const char* name) {
  ros::init(argc, argv, name);
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  try {
    Node node(nh, pnh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("geofusion: " << e.what());
    return 1;
  }
  return 0;
}

}  // namespace geofusion
