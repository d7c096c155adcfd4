// Writes recordings with the topics and frames of a Fetch robot's head camera (REP-103/105):
// RGB, registered depth (32FC1 metres or 16UC1 millimetres), camera_info, detections, odometry,
// /tf and /tf_static. One implementation for every tool that writes bags (make_synthetic_bag,
// generate_dataset).
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/common/lens.h"
#include "geofusion/common/measurement.h"
#include "geofusion/common/robot_names.h"

#include <ros/time.h>
#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace rosbag {
class Bag;
}

namespace geofusion {

struct RecordingLayout {
  std::string rgb_topic = std::string("/") + kRgbTopic;
  std::string rgb_info_topic = std::string("/") + kRgbInfoTopic;
  std::string depth_topic = std::string("/") + kDepthTopic;
  std::string depth_info_topic = std::string("/") + kDepthInfoTopic;
  std::string detections_topic = std::string("/") + kDetectionsTopic;
  std::string odom_topic = std::string("/") + kOdomTopic;
  std::string odom_frame = kOdomFrame;
  std::string base_frame = kBaseFrame;
  std::string camera_link_frame = kCameraLinkFrame;
  std::string optical_frame = kOpticalFrame;
  std::string depth_encoding = "32FC1";  ///< or 16UC1 (millimetres, 0 = no reading)
  bool lz4 = false;                      ///< LZ4-compressed bag chunks
};

class RecordingWriter {
 public:
  RecordingWriter();
  ~RecordingWriter();
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  /// False with `error` set when the file cannot be written or the layout is invalid.
  bool open(const std::string& path, const RecordingLayout& layout, std::string* error);
  void close();
  const RecordingLayout& layout() const { return layout_; }

  /// /tf_static: head_camera_link -> optical frame (and base -> head_camera_link when the head
  /// does not move).
  void writeStaticTransforms(const ros::Time& stamp, const Eigen::Isometry3d& T_link_optical,
                             const Eigen::Isometry3d* T_base_link = nullptr);
  /// /tf: odom -> base_link and, when given, the moving head base_link -> head_camera_link.
  void writeTransforms(const ros::Time& stamp, const Eigen::Isometry3d& T_odom_base,
                       const Eigen::Isometry3d* T_base_link = nullptr);
  /// /tf: odom -> the optical frame, for a hand-held camera (no robot base, no wheel odometry):
  /// the camera's own trajectory (imported datasets, docs/dataset.md "Real recordings").
  void writeCameraPose(const ros::Time& stamp, const Eigen::Isometry3d& T_odom_optical);
  /// nav_msgs/Odometry; twist from the previous call's pose (in the child frame), covariances
  /// of a wheel odometry (documented in docs/dataset.md).
  void writeOdometry(const ros::Time& stamp, const Eigen::Isometry3d& T_odom_base);
  /// RGB (rgb8, 3 bytes a pixel), registered depth in metres (0 = no reading) and both
  /// camera_infos, all stamped `stamp` in the optical frame.
  /// `lens`: the distortion the images were taken with (camera_info's plumb_bob D; none: zeros).
  void writeImages(const ros::Time& stamp, const PinholeIntrinsics& K,
                   const std::vector<std::uint8_t>& rgb, const std::vector<float>& depth,
                   const LensDistortion& lens = LensDistortion{});
  /// DetectionArray in the optical frame; header stamp `stamp`, written at `write_time`.
  void writeDetections(const ros::Time& stamp, const ros::Time& write_time,
                       const std::vector<RawDetection>& detections);

 private:
  std::unique_ptr<rosbag::Bag> bag_;
  RecordingLayout layout_;
  bool have_previous_odom_ = false;
  ros::Time previous_stamp_;
  Eigen::Isometry3d previous_odom_ = Eigen::Isometry3d::Identity();
};

}  // namespace geofusion
