// Reading private parameters into core Config structs, with validation at the edge.
#pragma once

#include <ros/ros.h>

#include <string>

namespace geofusion {

/// Reads ~name; a value below `min_value` is refused with a warning and the default is used.
template <typename T>
T paramAtLeast(const ros::NodeHandle& pnh, const std::string& name, T default_value, T min_value) {
  T value = default_value;
  pnh.param(name, value, default_value);
  if (value < min_value) {
    ROS_WARN_STREAM("geofusion: parameter " << pnh.resolveName(name) << " = " << value
                                            << " is below " << min_value << "; using "
                                            << default_value);
    value = default_value;
  }
  return value;
}

}  // namespace geofusion
