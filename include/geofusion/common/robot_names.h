// The robot's topic and frame names, in one place: the Fetch robot's head camera, odometry and
// frames. Every node's defaults, the tools' defaults, the recordings the generator writes and the
// tests take them from here; launch files and Python tests from config/robots/fetch.yaml, which a
// test (test_robot_names) holds equal to these. Topics are relative (resolved in a node's
// namespace); recordings are written under "/" + name.
#pragma once

namespace geofusion {

constexpr const char* kRgbTopic = "head_camera/rgb/image_raw";
constexpr const char* kRgbInfoTopic = "head_camera/rgb/camera_info";
constexpr const char* kDepthTopic = "head_camera/depth_registered/image_raw";
constexpr const char* kDepthInfoTopic = "head_camera/depth_registered/camera_info";
constexpr const char* kCameraInfoTopic = kRgbInfoTopic;  ///< the one the nodes use
constexpr const char* kDetectionsTopic = "detections";
constexpr const char* kOdomTopic = "odom";  ///< the robot's wheel odometry (nav_msgs/Odometry)

constexpr const char* kMapFrame = "map";
constexpr const char* kOdomFrame = "odom";
constexpr const char* kBaseFrame = "base_link";
constexpr const char* kCameraLinkFrame = "head_camera_link";
constexpr const char* kOpticalFrame = "head_camera_rgb_optical_frame";

}  // namespace geofusion
