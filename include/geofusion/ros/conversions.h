// Messages <-> core types. The only place the ROS layer touches message fields one by one.
#pragma once

#include "geofusion/core/measurement.h"

#include <geofusion/DetectionArray.h>
#include <geometry_msgs/Pose.h>

#include <vector>

namespace geofusion {

/// The raw detection, unchecked: NaNs and non-unit quaternions pass through to the core's check.
RawDetection fromMsg(const geofusion::Detection& msg);
std::vector<RawDetection> fromMsg(const geofusion::DetectionArray& msg);

geofusion::Detection toMsg(const RawDetection& detection);
geometry_msgs::Pose toPoseMsg(const Eigen::Isometry3d& T);

}  // namespace geofusion
