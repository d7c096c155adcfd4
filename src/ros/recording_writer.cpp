#include "geofusion/ros/recording_writer.h"

#include "geofusion/ros/conversions.h"

#include <geofusion/DetectionArray.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace geofusion {
namespace {

geometry_msgs::TransformStamped transform(const Eigen::Isometry3d& T, const ros::Time& stamp,
                                          const std::string& parent, const std::string& child) {
  geometry_msgs::TransformStamped t = tf2::eigenToTransform(T);
  t.header.stamp = stamp;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  return t;
}

// Wheel odometry uncertainty as a Fetch base reports it (variances; x, y, yaw).
constexpr double kPoseVarianceXY = 1e-4, kPoseVarianceYaw = 4e-4, kTwistVarianceXY = 1e-3,
                 kTwistVarianceYaw = 4e-3, kUnused = 1e6;

}  // namespace

RecordingWriter::RecordingWriter() = default;
RecordingWriter::~RecordingWriter() {
  close();
}

bool RecordingWriter::open(const std::string& path, const RecordingLayout& layout,
                           std::string* error) {
  if (layout.depth_encoding != "32FC1" && layout.depth_encoding != "16UC1") {
    if (error) *error = "depth encoding must be 32FC1 or 16UC1, not " + layout.depth_encoding;
    return false;
  }
  close();
  layout_ = layout;
  have_previous_odom_ = false;
  auto bag = std::make_unique<rosbag::Bag>();
  try {
    bag->open(path, rosbag::bagmode::Write);
    if (layout.lz4) bag->setCompression(rosbag::compression::LZ4);
  } catch (const std::exception& e) {
    if (error) *error = "cannot write " + path + ": " + e.what();
    return false;
  }
  bag_ = std::move(bag);
  return true;
}

void RecordingWriter::close() {
  if (bag_) bag_->close();
  bag_.reset();
}

void RecordingWriter::writeStaticTransforms(const ros::Time& stamp,
                                            const Eigen::Isometry3d& T_link_optical,
                                            const Eigen::Isometry3d* T_base_link) {
  tf2_msgs::TFMessage statics;
  if (T_base_link) {
    statics.transforms.push_back(
        transform(*T_base_link, stamp, layout_.base_frame, layout_.camera_link_frame));
  }
  statics.transforms.push_back(
      transform(T_link_optical, stamp, layout_.camera_link_frame, layout_.optical_frame));
  bag_->write("/tf_static", stamp, statics);
}

void RecordingWriter::writeTransforms(const ros::Time& stamp, const Eigen::Isometry3d& T_odom_base,
                                      const Eigen::Isometry3d* T_base_link) {
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(transform(T_odom_base, stamp, layout_.odom_frame, layout_.base_frame));
  if (T_base_link) {
    tf.transforms.push_back(
        transform(*T_base_link, stamp, layout_.base_frame, layout_.camera_link_frame));
  }
  bag_->write("/tf", stamp, tf);
}

void RecordingWriter::writeCameraPose(const ros::Time& stamp,
                                      const Eigen::Isometry3d& T_odom_optical) {
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(
      transform(T_odom_optical, stamp, layout_.odom_frame, layout_.optical_frame));
  bag_->write("/tf", stamp, tf);
}

void RecordingWriter::writeOdometry(const ros::Time& stamp, const Eigen::Isometry3d& T_odom_base) {
  nav_msgs::Odometry msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = layout_.odom_frame;
  msg.child_frame_id = layout_.base_frame;
  msg.pose.pose = toPoseMsg(T_odom_base);
  const double dt = have_previous_odom_ ? (stamp - previous_stamp_).toSec() : 0.0;
  msg.twist.twist = twistBetween(previous_odom_, T_odom_base, dt);
  const double pose_var[6] = {kPoseVarianceXY, kPoseVarianceXY, kUnused,
                              kUnused,         kUnused,         kPoseVarianceYaw};
  const double twist_var[6] = {kTwistVarianceXY, kTwistVarianceXY, kUnused,
                               kUnused,          kUnused,          kTwistVarianceYaw};
  for (int i = 0; i < 6; ++i) {
    msg.pose.covariance[static_cast<std::size_t>(7 * i)] = pose_var[i];
    msg.twist.covariance[static_cast<std::size_t>(7 * i)] = twist_var[i];
  }
  bag_->write(layout_.odom_topic, stamp, msg);
  have_previous_odom_ = true;
  previous_stamp_ = stamp;
  previous_odom_ = T_odom_base;
}

void RecordingWriter::writeImages(const ros::Time& stamp, const PinholeIntrinsics& K,
                                  const std::vector<std::uint8_t>& rgb,
                                  const std::vector<float>& depth, const LensDistortion& lens) {
  sensor_msgs::Image image;
  image.header.stamp = stamp;
  image.header.frame_id = layout_.optical_frame;
  image.width = static_cast<uint32_t>(K.width);
  image.height = static_cast<uint32_t>(K.height);
  image.encoding = sensor_msgs::image_encodings::RGB8;
  image.step = 3 * image.width;
  image.data = rgb;
  bag_->write(layout_.rgb_topic, stamp, image);

  sensor_msgs::Image d;
  d.header = image.header;
  d.width = image.width;
  d.height = image.height;
  if (layout_.depth_encoding == "32FC1") {
    d.encoding = sensor_msgs::image_encodings::TYPE_32FC1;
    d.step = 4 * d.width;
    d.data.resize(depth.size() * sizeof(float));
    std::memcpy(d.data.data(), depth.data(), d.data.size());
  } else {
    d.encoding = sensor_msgs::image_encodings::TYPE_16UC1;
    d.step = 2 * d.width;
    std::vector<uint16_t> mm(depth.size());
    for (std::size_t i = 0; i < mm.size(); ++i) {
      const double z = std::isfinite(depth[i]) && depth[i] > 0.f ? depth[i] * 1000.0 : 0.0;
      mm[i] = static_cast<uint16_t>(std::lround(std::min(z, 65535.0)));
    }
    d.data.resize(mm.size() * sizeof(uint16_t));
    std::memcpy(d.data.data(), mm.data(), d.data.size());
  }
  bag_->write(layout_.depth_topic, stamp, d);

  sensor_msgs::CameraInfo info;
  info.header = image.header;
  info.width = image.width;
  info.height = image.height;
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);
  if (lens.any()) {
    info.D = lens.D;
    if (lens.D.size() == 8) info.distortion_model = "rational_polynomial";
  }
  info.K = {K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {K.fx, 0, K.cx, 0, 0, K.fy, K.cy, 0, 0, 0, 1, 0};
  bag_->write(layout_.rgb_info_topic, stamp, info);
  bag_->write(layout_.depth_info_topic, stamp, info);
}

void RecordingWriter::writeDetections(const ros::Time& stamp, const ros::Time& write_time,
                                      const std::vector<RawDetection>& detections) {
  geofusion::DetectionArray msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = layout_.optical_frame;
  for (const RawDetection& d : detections) msg.detections.push_back(toMsg(d));
  bag_->write(layout_.detections_topic, write_time, msg);
}

}  // namespace geofusion
