#include "geofusion/ros/visual_odometry_node.h"

#include "geofusion/ros/conversions.h"
#include "geofusion/ros/node_config.h"
#include "geofusion/ros/tf_lookup.h"

#include <tf2_eigen/tf2_eigen.h>

#include <algorithm>
#include <cmath>

namespace geofusion {

namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d S;
  S << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return S;
}

using Matrix6d = Eigen::Matrix<double, 6, 6>;

void fill(const Matrix6d& m, boost::array<double, 36>* out) {
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) (*out)[static_cast<std::size_t>(6 * r + c)] = m(r, c);
}

}  // namespace

VisualOdometryNode::VisualOdometryNode(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh), pnh_(pnh), tf_listener_(tf_buffer_), diagnostics_(nh, pnh) {
  pnh_.param<std::string>("odom_frame", odom_frame_, kOdomFrame);
  pnh_.param<std::string>("base_frame", base_frame_, kBaseFrame);
  pnh_.param("publish_tf", publish_tf_, true);  // a launch choice (vo_publish_tf)
  const GeoFusionConfig config = loadNodeConfig(pnh_, {"publish_tf"});
  tf_timeout_s_ = config.input.tf_timeout_s;
  warn_period_s_ = config.input.warn_period_s;
  vo_ = std::make_unique<VisualOdometry>(config.visual_odometry);
  publishEffectiveConfig(pnh_, config);

  odom_pub_ = pnh_.advertise<nav_msgs::Odometry>("odom", 10);
  // RGB-D without detections, through the same synchronised input path as the estimator.
  subscriber_ = std::make_unique<RgbdSubscriber>(
      nh_, RgbdSubscriber::configOf(pnh_, config.input, false),
      [this](const sensor_msgs::ImageConstPtr& rgb, const sensor_msgs::ImageConstPtr& depth,
             const sensor_msgs::CameraInfoConstPtr& info,
             const geofusion::DetectionArrayConstPtr&) { onFrame(rgb, depth, info); },
      [this](const ros::Time& from, const ros::Time& to) { onTimeJump(from, to); });

  diagnostics_.setHardwareID("geofusion");
  diagnostics_.add("visual odometry", this, &VisualOdometryNode::diagnose);
  diagnostics_timer_ = pnh_.createWallTimer(
      ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) { diagnostics_.force_update(); });
  ROS_INFO_STREAM("geofusion: visual odometry on "
                  << subscriber_->topics()[0] << ", " << subscriber_->topics()[1] << "; publishing "
                  << odom_pub_.getTopic() << " and " << (publish_tf_ ? "" : "no ") << "TF "
                  << odom_frame_ << " -> " << (base_frame_.empty() ? "camera" : base_frame_));
}

// Time went back (a looping bag, a restarted driver; the subscriber has warned): the odometry
// restarts at the next frame.
void VisualOdometryNode::onTimeJump(const ros::Time&, const ros::Time&) {
  std::lock_guard<std::mutex> lock(mutex_);
  ROS_WARN("geofusion: visual odometry restarts after the jump back in time");
  started_ = false;
  have_last_ = false;
}

void VisualOdometryNode::onFrame(const sensor_msgs::ImageConstPtr& rgb,
                                 const sensor_msgs::ImageConstPtr& depth,
                                 const sensor_msgs::CameraInfoConstPtr& info) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++frames_;
  const ros::Time stamp = rgb->header.stamp;
  std::vector<std::uint8_t> gray;
  std::vector<float> metres;
  std::string error;
  if (!odometryImages(*rgb, *depth, *info, &camera_, &gray, &metres, &error)) {
    ++skipped_;
    ROS_WARN_STREAM_THROTTLE(warn_period_s_, "geofusion: visual odometry skipped a frame: "
                                                 << error << " (" << skipped_ << " so far)");
    return;
  }
  // The camera's place on the robot: base -> camera from TF (the head may move).
  const std::string& camera_frame = rgb->header.frame_id;
  Eigen::Isometry3d T_base_cam = Eigen::Isometry3d::Identity();
  if (!base_frame_.empty() &&
      !lookupTransformWallTimeout(tf_buffer_, base_frame_, camera_frame, stamp, tf_timeout_s_,
                                  &T_base_cam, &error) &&
      !lookupTransformWallTimeout(tf_buffer_, base_frame_, camera_frame, ros::Time(0), 0.0,
                                  &T_base_cam, &error)) {
    ++skipped_;
    ROS_WARN_STREAM_THROTTLE(warn_period_s_, "geofusion: visual odometry skipped a frame, no TF "
                                                 << base_frame_ << " -> " << camera_frame << ": "
                                                 << error);
    return;
  }
  if (!started_) {
    // odom starts where the base is: the camera starts at base -> camera.
    vo_->reset(T_base_cam);
    started_ = true;
  }
  const PinholeIntrinsics& K = camera_.K();
  const VoFrameResult r = vo_->track(
      GrayImageView{gray.data(), static_cast<int>(rgb->width), static_cast<int>(rgb->height), 0},
      DepthImageView{metres.data(), static_cast<int>(depth->width),
                     static_cast<int>(depth->height)},
      K, stamp.toSec());
  last_ = r;
  recent_ms_.push_back(r.time_ms);
  if (recent_ms_.size() > 100) recent_ms_.erase(recent_ms_.begin());
  if (!r.pose_valid) {
    ++lost_;
    ROS_WARN_STREAM_THROTTLE(
        warn_period_s_, "geofusion: visual odometry lost: " << r.problem << " (" << lost_
                                                            << " frames without a pose so far)");
    return;
  }
  const bool discontinuous = r.restarted && have_last_;
  if (discontinuous) {
    ++restarts_;
    ROS_WARN_STREAM(
        "geofusion: visual odometry restarted a new map at the last known pose; the "
        "pose covariance grew by the restart sigmas (no motion is published for "
        "the jump)");
  }
  if (r.by_depth) {
    ++by_depth_;
    ROS_INFO_STREAM_THROTTLE(warn_period_s_,
                             "geofusion: visual odometry placed a frame by its "
                             "depth alone (features: "
                                 << r.problem << "; " << by_depth_ << " frames so far)");
  }
  if (r.relocalised) {
    ++relocalisations_;
    ROS_INFO_STREAM("geofusion: visual odometry relocalised against its map");
  }

  // The child frame: the base (camera pose through the base -> camera transform) or the camera.
  const bool to_base = !base_frame_.empty();
  const Eigen::Isometry3d T_cam_child =
      to_base ? T_base_cam.inverse() : Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d T_odom_child = r.T_odom_cam * T_cam_child;
  // Covariance of the child pose: the camera's, moved along the lever arm camera -> child.
  Matrix6d J = Matrix6d::Identity();
  J.topRightCorner<3, 3>() = -skew(r.T_odom_cam.linear() * T_cam_child.translation());
  Matrix6d cov = J * r.covariance * J.transpose();
  cov.diagonal().array() += 1e-9;  // never singular, even at the first frame that defines odom

  nav_msgs::Odometry odom;
  odom.header.stamp = stamp;
  odom.header.frame_id = odom_frame_;
  odom.child_frame_id = to_base ? base_frame_ : camera_frame;
  odom.pose.pose = toPoseMsg(T_odom_child);
  fill(cov, &odom.pose.covariance);
  // Twist in the child frame from the last pose; none across a restart (its covariance says so).
  const double dt = have_last_ ? (stamp - last_stamp_).toSec() : 0.0;
  Matrix6d twist_cov = Matrix6d::Identity() * 1e3;
  if (have_last_ && !discontinuous && dt > 1e-4) {
    odom.twist.twist = twistBetween(T_last_odom_child_, T_odom_child, dt);
    twist_cov = 2.0 * r.frame_covariance / (dt * dt);
  }
  fill(twist_cov, &odom.twist.covariance);
  odom_pub_.publish(odom);
  if (publish_tf_) {
    geometry_msgs::TransformStamped t = tf2::eigenToTransform(T_odom_child);
    t.header = odom.header;
    t.child_frame_id = odom.child_frame_id;
    tf_broadcaster_.sendTransform(t);
  }
  T_last_odom_child_ = T_odom_child;
  last_stamp_ = stamp;
  have_last_ = true;
}

void VisualOdometryNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (frames_ == 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no synchronised RGB-D input yet");
  } else if (last_.state == TrackingState::kLost) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "lost: " + last_.problem);
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, toString(last_.state));
  }
  std::vector<double> ms = recent_ms_;
  std::sort(ms.begin(), ms.end());
  status.add("frames", frames_);
  status.add("frames without a pose", lost_);
  status.add("frames placed by depth alone", by_depth_);
  status.add("frames skipped (input, TF)", skipped_);
  status.add("restarts", restarts_);
  status.add("relocalisations", relocalisations_);
  status.add("keyframes in the local map", vo_->numKeyframes());
  status.add("features", last_.features);
  status.add("features with depth", last_.features_with_depth);
  status.add("inliers", last_.inliers);
  status.add("median ms per frame (last 100)", ms.empty() ? 0.0 : ms[ms.size() / 2]);
}

}  // namespace geofusion
