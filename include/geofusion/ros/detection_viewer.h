// The frame-by-frame view: each synchronised RGB-D frame's detections, checked and placed in the
// odometry frame through TF, published as rviz markers. Run as a nodelet
// (geofusion/DetectionViewerNodelet) or as a node (detection_viewer_node).
#pragma once

#include "geofusion/estimation/frame_by_frame.h"
#include "geofusion/ros/rgbd_subscriber.h"

#include <dynamic_reconfigure/server.h>
#include <geofusion/DetectionViewerConfig.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <boost/thread/recursive_mutex.hpp>

#include <memory>
#include <mutex>
#include <string>

namespace geofusion {

class DetectionViewer {
 public:
  DetectionViewer(ros::NodeHandle nh, ros::NodeHandle pnh);
  ~DetectionViewer();

 private:
  void onFrame(const sensor_msgs::ImageConstPtr& rgb, const sensor_msgs::ImageConstPtr& depth,
               const sensor_msgs::CameraInfoConstPtr& info,
               const geofusion::DetectionArrayConstPtr& dets);
  void onTimeJump(const ros::Time& from, const ros::Time& to);
  void onReconfigure(geofusion::DetectionViewerConfig& config, uint32_t level);
  void logSummary(const ros::WallTimerEvent&);

  ros::NodeHandle nh_;
  ros::NodeHandle pnh_;
  std::string odom_frame_;
  double warn_period_s_ = 5.0;

  mutable std::mutex mutex_;  // guards everything below that reconfigure or onFrame touch
  FrameByFrame fbf_;
  double axis_length_m_ = 0.05;
  double tf_timeout_s_ = 0.1;
  DetectionTally tally_;
  std::size_t tf_failures_ = 0;
  std::size_t bad_images_ = 0;
  std::size_t logged_frames_ = 0;  // tally_.frames at the last summary

  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  ros::Publisher markers_pub_;
  ros::WallTimer summary_timer_;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<geofusion::DetectionViewerConfig>> reconfigure_;
  std::unique_ptr<RgbdSubscriber> subscriber_;
};

}  // namespace geofusion
