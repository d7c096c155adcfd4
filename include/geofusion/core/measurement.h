// Core (ROS-free) types for per-frame object detections.
#pragma once

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace geofusion {

/// A 2D box in image pixels; width or height of 0 means "no box".
struct PixelBox {
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;
  bool valid() const { return width > 0 && height > 0; }
};

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
