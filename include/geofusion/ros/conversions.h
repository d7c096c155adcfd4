// Messages <-> core types. The only place the ROS layer touches message fields one by one.
#pragma once

#include "geofusion/common/measurement.h"

#include "geofusion/common/camera.h"

#include <geofusion/DetectionArray.h>
#include <geometry_msgs/Point.h>
#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Twist.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <cstdint>
#include <string>
#include <vector>

namespace geofusion {

/// The raw detection, unchecked: NaNs and non-unit quaternions pass through to the core's check.
RawDetection fromMsg(const geofusion::Detection& msg);
std::vector<RawDetection> fromMsg(const geofusion::DetectionArray& msg);

geofusion::Detection toMsg(const RawDetection& detection);
geometry_msgs::Pose toPoseMsg(const Eigen::Isometry3d& T);
geometry_msgs::Point toPointMsg(const Eigen::Vector3d& p);
/// Twist in the moving frame that takes `from` to `to` in `dt` seconds (zero for dt <= 0).
geometry_msgs::Twist twistBetween(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to,
                                  double dt);

/// Why a depth image cannot be used (empty, encoding other than 32FC1 metres / 16UC1
/// millimetres, data shorter than step * height), or nullptr.
const char* depthProblem(const sensor_msgs::Image& depth);
/// Depth in metres, row-major, 0 = no reading (NaN, inf, non-positive and 16-bit 0 become 0).
/// False when depthProblem() says the image is unusable.
bool depthToMetres(const sensor_msgs::Image& depth, std::vector<float>* metres);
/// The image as 8-bit grey, row-major without padding (cv_bridge: mono8 as is, colour and 16-bit
/// converted). False, with the reason, for an empty or unconvertible image.
bool toGray(const sensor_msgs::Image& image, std::vector<std::uint8_t>* gray, std::string* error);
/// Pinhole intrinsics from the K matrix (distortion is ignored: registered, rectified depth).
PinholeIntrinsics intrinsicsFromCameraInfo(const sensor_msgs::CameraInfo& info);

}  // namespace geofusion
