// RGB-D visual odometry on a robot: synchronised RGB, registered depth and camera_info in;
// nav_msgs/Odometry and TF odom -> base (through TF's base -> camera; odom -> camera when no base
// frame is given) out, REP-105. Run as a nodelet (geofusion/VisualOdometryNodelet) or a node
// (visual_odometry_node). The tracking itself is the ROS-free VisualOdometry.
#pragma once

#include "geofusion/odometry/visual_odometry.h"
#include "geofusion/ros/conversions.h"
#include "geofusion/ros/rgbd_subscriber.h"

#include <diagnostic_updater/diagnostic_updater.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace geofusion {

class VisualOdometryNode {
 public:
  VisualOdometryNode(ros::NodeHandle nh, ros::NodeHandle pnh);

 private:
  void onTimeJump(const ros::Time& from, const ros::Time& to);
  void onFrame(const sensor_msgs::ImageConstPtr& rgb, const sensor_msgs::ImageConstPtr& depth,
               const sensor_msgs::CameraInfoConstPtr& info);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  ros::NodeHandle nh_, pnh_;
  std::string odom_frame_, base_frame_;
  bool publish_tf_ = true;
  double tf_timeout_s_ = 0.1, warn_period_s_ = 5.0;

  std::mutex mutex_;
  CameraRectifier camera_;  ///< K and the lens of camera_info; raw images made pinhole
  std::unique_ptr<VisualOdometry> vo_;
  bool started_ = false;
  ros::Time last_stamp_;
  bool have_last_ = false;
  Eigen::Isometry3d T_last_odom_child_ = Eigen::Isometry3d::Identity();
  VoFrameResult last_;
  std::size_t frames_ = 0, lost_ = 0, by_depth_ = 0, restarts_ = 0, relocalisations_ = 0,
              skipped_ = 0;
  std::vector<double> recent_ms_;

  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  ros::Publisher odom_pub_;
  std::unique_ptr<RgbdSubscriber> subscriber_;
  diagnostic_updater::Updater diagnostics_;
  ros::WallTimer diagnostics_timer_;
};

}  // namespace geofusion
