// Core (ROS-free) types for per-frame object detections.
#pragma once

#include "geofusion/common/camera.h"

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace geofusion {

/// A detection as it arrives from the perception stack, before any check: the pose is raw
/// (it may hold NaNs or a non-unit quaternion). Mirrors geofusion/Detection.msg.
struct RawDetection {
  std::string class_name;
  int class_id = -1;
  double score = 0.0;
  Eigen::Vector3d position_cam = Eigen::Vector3d::Zero();  ///< metres, camera optical frame
  Eigen::Quaterniond orientation_cam = Eigen::Quaterniond::Identity();  ///< raw, unnormalised
  PixelBox box;
};

/// A checked object measurement z_t^k: class and a proper rigid pose in the camera frame.
struct ObjectMeasurement {
  std::string class_name;
  int class_id = -1;
  double score = 0.0;
  Eigen::Isometry3d T_cam_obj = Eigen::Isometry3d::Identity();
  PixelBox box;
};

}  // namespace geofusion
