#include "geofusion/ros/detection_viewer.h"

#include "geofusion/ros/conversions.h"
#include "geofusion/ros/markers.h"
#include "geofusion/ros/node_config.h"
#include "geofusion/ros/params.h"
#include "geofusion/ros/tf_lookup.h"

#include <sensor_msgs/image_encodings.h>
#include <visualization_msgs/MarkerArray.h>

namespace geofusion {

DetectionViewer::DetectionViewer(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh), pnh_(pnh), tf_listener_(tf_buffer_) {
  pnh_.param<std::string>("odom_frame", odom_frame_, kOdomFrame);
  const GeoFusionConfig config = loadNodeConfig(pnh_, {"axis_length_m", "summary_period_s"});
  warn_period_s_ = config.input.warn_period_s;
  const FrameByFrame::Config fbf = config.checks;
  fbf_.setConfig(fbf);
  axis_length_m_ = paramAtLeast(pnh_, "axis_length_m", 0.05, 0.005);
  tf_timeout_s_ = config.input.tf_timeout_s;

  const RgbdSubscriber::Config sub = RgbdSubscriber::configOf(pnh_, config.input);
  publishEffectiveConfig(pnh_, config);

  markers_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("detection_markers", 5);

  reconfigure_ = std::make_unique<dynamic_reconfigure::Server<geofusion::DetectionViewerConfig>>(
      reconfigure_mutex_, pnh_);
  geofusion::DetectionViewerConfig initial;
  initial.min_score = fbf.min_score;
  initial.max_range_m = fbf.max_range_m;
  initial.axis_length_m = axis_length_m_;
  initial.tf_timeout_s = tf_timeout_s_;
  reconfigure_->updateConfig(initial);
  reconfigure_->setCallback(
      [this](geofusion::DetectionViewerConfig& c, uint32_t level) { onReconfigure(c, level); });

  subscriber_ = std::make_unique<RgbdSubscriber>(
      nh_, sub,
      [this](const sensor_msgs::ImageConstPtr& rgb, const sensor_msgs::ImageConstPtr& depth,
             const sensor_msgs::CameraInfoConstPtr& info,
             const geofusion::DetectionArrayConstPtr& dets) { onFrame(rgb, depth, info, dets); },
      [this](const ros::Time& from, const ros::Time& to) { onTimeJump(from, to); });
  const double summary_period_s = paramAtLeast(pnh_, "summary_period_s", 10.0, 0.0);
  if (summary_period_s > 0) {
    summary_timer_ = pnh_.createWallTimer(ros::WallDuration(summary_period_s),
                                          &DetectionViewer::logSummary, this);
  }
  ROS_INFO("geofusion: detection viewer publishing %s in frame '%s'",
           markers_pub_.getTopic().c_str(), odom_frame_.c_str());
}

DetectionViewer::~DetectionViewer() {
  subscriber_.reset();  // no more callbacks from here on
  std::lock_guard<std::mutex> lock(mutex_);
  ROS_INFO("geofusion: detection viewer summary: %s; %zu frame(s) without TF, %zu bad image(s)",
           tally_.summary().c_str(), tf_failures_, bad_images_);
}

void DetectionViewer::logSummary(const ros::WallTimerEvent&) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (tally_.frames + tf_failures_ + bad_images_ == logged_frames_) return;  // nothing new
  logged_frames_ = tally_.frames + tf_failures_ + bad_images_;
  ROS_INFO("geofusion: detection viewer so far: %s; %zu frame(s) without TF, %zu bad image(s)",
           tally_.summary().c_str(), tf_failures_, bad_images_);
}

void DetectionViewer::onReconfigure(geofusion::DetectionViewerConfig& config, uint32_t) {
  std::lock_guard<std::mutex> lock(mutex_);
  FrameByFrame::Config fbf = fbf_.config();
  fbf.min_score = config.min_score;
  fbf.max_range_m = config.max_range_m;
  fbf_.setConfig(fbf);
  axis_length_m_ = config.axis_length_m;
  tf_timeout_s_ = config.tf_timeout_s;
}

void DetectionViewer::onTimeJump(const ros::Time&, const ros::Time&) {
  // Transforms from the "future" would make every lookup wrong: start TF afresh.
  tf_buffer_.clear();
}

void DetectionViewer::onFrame(const sensor_msgs::ImageConstPtr& /*rgb*/,
                              const sensor_msgs::ImageConstPtr& depth,
                              const sensor_msgs::CameraInfoConstPtr& /*info*/,
                              const geofusion::DetectionArrayConstPtr& dets) {
  if (const char* problem = depthProblem(*depth)) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++bad_images_;
    ROS_WARN_THROTTLE(warn_period_s_, "geofusion: %s (encoding '%s', %ux%u) at %.3f; frame skipped",
                      problem, depth->encoding.c_str(), depth->width, depth->height,
                      depth->header.stamp.toSec());
    return;
  }
  const std::string& camera_frame = dets->header.frame_id;
  if (camera_frame.empty()) {
    ROS_WARN_THROTTLE(warn_period_s_,
                      "geofusion: DetectionArray at %.3f has no header.frame_id; frame skipped",
                      dets->header.stamp.toSec());
    return;
  }
  double tf_timeout_s;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    tf_timeout_s = tf_timeout_s_;
  }
  Eigen::Isometry3d T_odom_cam;
  std::string tf_error;
  if (!lookupTransformWallTimeout(tf_buffer_, odom_frame_, camera_frame, dets->header.stamp,
                                  tf_timeout_s, &T_odom_cam, &tf_error)) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++tf_failures_;
    ROS_WARN_THROTTLE(warn_period_s_,
                      "geofusion: no TF from '%s' to '%s' at %.3f (%zu frame(s) so far): %s; "
                      "frame skipped",
                      camera_frame.c_str(), odom_frame_.c_str(), dets->header.stamp.toSec(),
                      tf_failures_, tf_error.c_str());
    return;
  }

  std::vector<WorldDetection> world;
  DetectionTally frame_tally;
  double axis_length_m;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    world = fbf_.process(fromMsg(*dets), T_odom_cam, &frame_tally);
    tally_.add(frame_tally);
    axis_length_m = axis_length_m_;
  }
  if (frame_tally.totalSkipped() > 0) {
    ROS_WARN_THROTTLE(warn_period_s_, "geofusion: frame %.3f on %s: %s", dets->header.stamp.toSec(),
                      subscriber_->topics()[3].c_str(), frame_tally.summary().c_str());
  }
  std_msgs::Header header;
  header.stamp = dets->header.stamp;
  header.frame_id = odom_frame_;
  markers_pub_.publish(detectionMarkers(world, header, axis_length_m));
  ROS_INFO_ONCE("geofusion: first synchronised frame (%zu detection(s)) shown", world.size());
}

}  // namespace geofusion
