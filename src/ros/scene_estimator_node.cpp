#include "geofusion/ros/scene_estimator_node.h"

#include "geofusion/estimation/run_results.h"
#include "geofusion/ros/conversions.h"
#include "geofusion/ros/map_messages.h"
#include "geofusion/ros/node_config.h"
#include "geofusion/ros/params.h"
#include "geofusion/ros/tf_lookup.h"

#include <geofusion/ObjectMap.h>
#include <nav_msgs/Path.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_eigen/tf2_eigen.h>
#include <visualization_msgs/MarkerArray.h>
#ifdef GEOFUSION_HAVE_OCTOMAP_MSGS
#include <octomap_msgs/Octomap.h>
#endif

#include <algorithm>
#include <cmath>

namespace geofusion {

SceneEstimatorNode::SceneEstimatorNode(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh), pnh_(pnh), tf_listener_(tf_buffer_), diagnostics_(nh, pnh) {
  pnh_.param<std::string>("map_frame", map_frame_, kMapFrame);
  pnh_.param<std::string>("odom_frame", odom_frame_, kOdomFrame);
  config_ = loadNodeConfig(pnh_, {"odometry", "odom_topic"});
  // Where odometry comes from is the launch file's choice (odometry:=tf|topic|visual).
  pnh_.param<std::string>("odom_topic", odom_topic_, "");
  std::string odometry = odom_topic_.empty() ? "tf" : "topic";  // a plain node: ~odom_topic says
  pnh_.param<std::string>("odometry", odometry, odometry);
  if (odometry != "tf" && odometry != "topic" && odometry != "visual") {
    throw std::runtime_error(
        "~odometry (launch argument odometry): expected tf, topic or visual, "
        "got '" +
        odometry + "'; not starting");
  }
  if (odometry != "tf" && odom_topic_.empty()) {
    throw std::runtime_error("~odometry " + odometry +
                             " needs ~odom_topic (launch argument odom_topic); not starting");
  }
  if (odometry == "tf") odom_topic_.clear();
  publish_tf_ = config_.node.publish_map_to_odom;
  save_on_shutdown_ = config_.node.save_on_shutdown;
  tf_timeout_s_ = config_.input.tf_timeout_s;
  warn_period_s_ = config_.input.warn_period_s;
  background_publish_every_ = config_.node.background_publish_every;
  method_name_ = toString(config_.estimator.method);

  ModelSet models;
  std::vector<std::string> errors;
  if (!loadModelSet(config_.model_set.name, config_.model_set.dir, packageDir(), &models, &errors,
                    config_.model_set.surface_features)) {
    std::string all;
    for (const auto& e : errors) all += "\n  " + e;
    throw std::runtime_error("model_set.name: cannot load the model set '" +
                             config_.model_set.name + "', not starting:" + all);
  }
  for (const auto& e : errors) ROS_WARN_STREAM("geofusion: " << e);
  pipeline_ = std::make_unique<EstimatorPipeline>(
      models, config_.estimator, config_.keyframes, config_.checks,
      config_.background_enabled ? &config_.background : nullptr);

  map_pub_ = pnh_.advertise<geofusion::ObjectMap>("object_map", 1, true);
  markers_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("map_markers", 1, true);
  path_pub_ = pnh_.advertise<nav_msgs::Path>("trajectory", 1, true);
  background_markers_pub_ =
      pnh_.advertise<visualization_msgs::MarkerArray>("background_markers", 1, true);
  background_cloud_pub_ = pnh_.advertise<sensor_msgs::PointCloud2>("background_cloud", 1, true);
#ifdef GEOFUSION_HAVE_OCTOMAP_MSGS
  // Built against octomap_msgs: the tree itself, for octomap_rviz_plugins and OctoMap tools.
  background_octomap_pub_ = pnh_.advertise<octomap_msgs::Octomap>("background_octomap", 1, true);
#endif
  save_srv_ = pnh_.advertiseService("save_map", &SceneEstimatorNode::onSave, this);
  reset_srv_ = pnh_.advertiseService("reset", &SceneEstimatorNode::onReset, this);

  reconfigure_ = std::make_unique<dynamic_reconfigure::Server<geofusion::SceneEstimatorConfig>>(
      reconfigure_mutex_, pnh_);
  {
    // dynamic_reconfigure starts from the loaded configuration, never from its compiled defaults.
    geofusion::SceneEstimatorConfig initial = geofusion::SceneEstimatorConfig::__getDefault__();
    dynamic_reconfigure::Config values;
    initial.__toMessage__(values);
    for (const std::string& name : fillReconfigure(config_, &values))
      ROS_ERROR_STREAM("geofusion: cfg/SceneEstimator.cfg has '" << name << "', no setting has");
    initial.__fromMessage__(values);
    reconfigure_->updateConfig(initial);
  }
  reconfigure_->setCallback(
      [this](geofusion::SceneEstimatorConfig& c, uint32_t level) { onReconfigure(c, level); });

  diagnostics_.setHardwareID("geofusion");
  diagnostics_.add("scene estimator", this, &SceneEstimatorNode::diagnose);
  diagnostics_timer_ = pnh_.createWallTimer(
      ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) { diagnostics_.force_update(); });

  if (!odom_topic_.empty()) {
    ros::NodeHandle odom_nh(nh_);
    odom_nh.setCallbackQueue(&odom_queue_);
    odom_sub_ = odom_nh.subscribe(odom_topic_, 200, &SceneEstimatorNode::onOdometry, this);
    odom_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &odom_queue_);
    odom_spinner_->start();
    ROS_INFO_STREAM("geofusion: odometry from " << odom_sub_.getTopic()
                                                << " (nav_msgs/Odometry) instead of TF's "
                                                << odom_frame_ << " -> base");
  }

  const RgbdSubscriber::Config sub = RgbdSubscriber::configOf(pnh_, config_.input);
  subscriber_ = std::make_unique<RgbdSubscriber>(
      nh_, sub,
      [this](const auto& rgb, const auto& depth, const auto& info, const auto& dets) {
        onFrame(rgb, depth, info, dets);
      },
      [this](const ros::Time& from, const ros::Time& to) { onTimeJump(from, to); });
  ROS_INFO_STREAM("geofusion: scene estimator (" << method_name_ << ", " << models.size()
                                                 << " classes from " << models.name()
                                                 << ") in frame " << map_frame_);
  publishEffectiveConfig(pnh_, config_);
}

SceneEstimatorNode::~SceneEstimatorNode() {
  subscriber_.reset();
  if (odom_spinner_) odom_spinner_->stop();
  odom_sub_.shutdown();
  if (!save_on_shutdown_.empty()) {
    std::string message;
    std::vector<std::string> files;
    save(save_on_shutdown_, &message, &files);
    ROS_INFO_STREAM("geofusion: " << message);
  }
}

void SceneEstimatorNode::onFrame(const sensor_msgs::ImageConstPtr& /*rgb*/,
                                 const sensor_msgs::ImageConstPtr& depth,
                                 const sensor_msgs::CameraInfoConstPtr& info,
                                 const geofusion::DetectionArrayConstPtr& dets) {
  Eigen::Isometry3d T_odom_cam;
  std::string error;
  bool have_pose = false;
  if (odom_topic_.empty()) {
    have_pose = lookupTransformWallTimeout(tf_buffer_, odom_frame_, dets->header.frame_id,
                                           dets->header.stamp, tf_timeout_s_, &T_odom_cam, &error);
  } else {
    // odom -> base from the odometry topic (its own buffer, so a recording's odom -> base on TF
    // cannot mix in), base -> camera from TF.
    Eigen::Isometry3d T_odom_base, T_base_cam;
    const std::string base = odom_base_frame_.get();
    have_pose = !base.empty() &&
                lookupTransformWallTimeout(odom_buffer_, odom_frame_, base, dets->header.stamp,
                                           tf_timeout_s_, &T_odom_base, &error) &&
                lookupTransformWallTimeout(tf_buffer_, base, dets->header.frame_id,
                                           dets->header.stamp, tf_timeout_s_, &T_base_cam, &error);
    if (base.empty()) error = "no odometry received on " + odom_sub_.getTopic() + " yet";
    T_odom_cam = T_odom_base * T_base_cam;
  }
  if (!have_pose) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++tf_failures_;
    ROS_WARN_STREAM_THROTTLE(warn_period_s_, "geofusion: frame skipped, no TF from "
                                                 << odom_frame_ << " to " << dets->header.frame_id
                                                 << ": " << error << " (" << tf_failures_
                                                 << " so far)");
    return;
  }
  KeyframeResult result;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++frames_;
    const auto outcome = pipeline_->process(*depth, *info, *dets, T_odom_cam, &result);
    if (outcome == EstimatorPipeline::Outcome::kBadDepth) {
      ++bad_depth_;
      ROS_WARN_STREAM_THROTTLE(warn_period_s_,
                               "geofusion: frame skipped: "
                                   << (depthProblem(*depth) ? depthProblem(*depth)
                                                            : "camera_info or depth size mismatch")
                                   << " (" << bad_depth_ << " so far)");
      return;
    }
    if (outcome != EstimatorPipeline::Outcome::kKeyframe) return;
    ++keyframes_;
    last_ = result;
    reportFailedStages(result);
    if (!result.detection_warning.empty())
      ROS_WARN_STREAM_THROTTLE(10.0, "geofusion: " << result.detection_warning);
  }
  std_msgs::Header header;
  header.stamp = dets->header.stamp;
  header.frame_id = map_frame_;
  publish(result, header);
  ROS_DEBUG_STREAM("geofusion: keyframe " << result.keyframe << ": " << result.objects.size()
                                          << " objects, " << result.timings.total_ms << " ms");
}

// A stage whose solve failed (its result not used) is counted for diagnostics and warned about.
void SceneEstimatorNode::reportFailedStages(const KeyframeResult& result) {
  for (const auto& [name, report] :
       {std::pair{"stage I", &result.stage_one}, std::pair{"stage II", &result.stage_two}}) {
    if (!report->failed()) continue;
    ++failed_stages_;
    ROS_WARN_STREAM_THROTTLE(5.0, "geofusion: " << name << " at keyframe " << result.keyframe << " "
                                                << toString(report->status)
                                                << "; its result is not used (" << failed_stages_
                                                << " failed stages so far)");
  }
}

void SceneEstimatorNode::publish(const KeyframeResult& result, const std_msgs::Header& header) {
  SupportPlane plane;
  Eigen::Vector3d gravity;
  std::vector<Eigen::Isometry3d> trajectory;
  std::vector<double> stamps;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    plane = pipeline_->estimator().supportPlane();
    gravity = pipeline_->estimator().config().gravity;
    trajectory = pipeline_->estimator().trajectory();
    stamps = pipeline_->estimator().keyframeStamps();
  }
  map_pub_.publish(toObjectMapMsg(result, plane, gravity, header));
  markers_pub_.publish(mapMarkers(result, plane, header));
  nav_msgs::Path path;
  path.header = header;
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    geometry_msgs::PoseStamped p;
    p.header.frame_id = map_frame_;
    p.header.stamp = ros::Time(stamps[i]);
    p.pose = toPoseMsg(trajectory[i]);
    path.poses.push_back(p);
  }
  path_pub_.publish(path);
  broadcastCorrection(header.stamp);
  // Every N-th keyframe from the first, and on a reset (an empty map).
  if ((keyframes_ - 1) % static_cast<std::size_t>(background_publish_every_) == 0 ||
      result.objects.empty()) {
    publishBackground(header);
  }
}

void SceneEstimatorNode::publishBackground(const std_msgs::Header& header) {
  std::vector<Eigen::Vector3d> centres;
  double resolution = 0.0;
  std::string octree;  // binary serialisation, only with octomap_msgs
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!pipeline_->background()) return;
    centres = pipeline_->background()->occupiedCentres();
    resolution = pipeline_->background()->config().resolution_m;
    if (background_octomap_pub_ && background_octomap_pub_.getNumSubscribers() > 0)
      octree = pipeline_->background()->binaryData();
  }
  background_markers_pub_.publish(backgroundMarkers(centres, resolution, header));
  background_cloud_pub_.publish(pointCloud(centres, header));
#ifdef GEOFUSION_HAVE_OCTOMAP_MSGS
  if (!octree.empty()) {
    octomap_msgs::Octomap msg;  // what octomap_msgs::binaryMapToMsg fills
    msg.header = header;
    msg.binary = true;
    msg.id = "OcTree";
    msg.resolution = resolution;
    msg.data.assign(octree.begin(), octree.end());
    background_octomap_pub_.publish(msg);
  }
#endif
}

void SceneEstimatorNode::broadcastCorrection(const ros::Time& stamp) {
  if (!publish_tf_) return;
  Eigen::Isometry3d T_map_odom;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    T_map_odom = pipeline_->estimator().T_map_odom();
  }
  geometry_msgs::TransformStamped t = tf2::eigenToTransform(T_map_odom);
  t.header.stamp = stamp;
  t.header.frame_id = map_frame_;
  t.child_frame_id = odom_frame_;
  tf_broadcaster_.sendTransform(t);
}

void SceneEstimatorNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  const StageTimings& t = last_.timings;
  if (frames_ == 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no synchronised input yet");
  } else if (last_.stage_one.failed() || last_.stage_two.failed()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "the last keyframe's optimisation failed; its result is not used");
  } else if (!last_.detection_warning.empty()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, last_.detection_warning);
  } else if (tf_failures_ + bad_depth_ > frames_ / 2) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "most frames skipped (missing TF or unusable depth)");
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "running");
  }
  status.add("method", method_name_);
  const double inconsistent_below = pipeline_->estimator().config().monitor.inconsistent_below;
  int refined = 0, rejected = 0;
  for (const DetectionReport& d : last_.detections) {
    refined += d.refinement == RefinementOutcome::kAccepted;
    rejected += d.consistency >= 0 && d.consistency < inconsistent_below;
  }
  status.add("detections (last keyframe)", last_.detections.size());
  status.add("depth-refined (last keyframe)", refined);
  status.add("inconsistent with depth (last keyframe)", rejected);
  status.add("synchronised frames", frames_);
  if (subscriber_) {
    // Input rates over the last diagnostics period; messages that never made a synchronised set
    // (the most frequent input's count minus the sets) are the synchroniser's drops.
    const std::vector<std::size_t> counts = subscriber_->messageCounts();
    const std::vector<std::string> topics = subscriber_->topics();
    const std::size_t synced = subscriber_->synchronizedCount();
    const ros::WallTime now = ros::WallTime::now();
    const double dt = last_rates_time_.isZero() ? 0.0 : (now - last_rates_time_).toSec();
    for (std::size_t i = 0; i < counts.size() && i < topics.size(); ++i) {
      const std::size_t before = i < last_counts_.size() ? last_counts_[i] : 0;
      const double rate = dt > 0.0 && counts[i] >= before ? (counts[i] - before) / dt : 0.0;
      status.addf("input rate " + topics[i], "%.1f Hz", rate);
    }
    const std::size_t most = counts.empty() ? 0 : *std::max_element(counts.begin(), counts.end());
    status.add("synchronised by the subscriber", synced);
    status.add("sync drops", most > synced ? most - synced : 0);
    last_counts_ = counts;
    last_rates_time_ = now;
  }
  status.add("keyframes", keyframes_);
  status.add("frames without TF", tf_failures_);
  status.add("frames with unusable depth", bad_depth_);
  status.add("detections", pipeline_->tally().summary());
  status.add("objects", last_.objects.size());
  status.add("contacts", last_.contacts.size());
  status.add("last keyframe: stage I", toString(last_.stage_one.status));
  status.add("last keyframe: stage II", toString(last_.stage_two.status));
  status.add("failed optimisation stages", failed_stages_);
  status.add("last keyframe ms: consistency", t.consistency_ms);
  status.add("last keyframe ms: association", t.association_ms);
  status.add("last keyframe ms: stage I", t.stage_one_ms);
  status.add("last keyframe ms: relations", t.relations_ms);
  status.add("last keyframe ms: stage II", t.stage_two_ms);
  status.add("last keyframe ms: total", t.total_ms);
  status.add("last keyframe ms: background", pipeline_->lastBackgroundMs());
}

void SceneEstimatorNode::onReconfigure(geofusion::SceneEstimatorConfig& values, uint32_t) {
  std::lock_guard<std::mutex> lock(mutex_);
  dynamic_reconfigure::Config message;
  values.__toMessage__(message);
  GeoFusionConfig changed = config_;
  for (const std::string& problem : applyReconfigure(message, &changed)) {
    ROS_WARN_STREAM("geofusion: dynamic_reconfigure: " << problem);
  }
  const std::string diff = configDiff(changed);
  const bool any_change = diff != configDiff(config_);
  config_ = changed;
  pipeline_->estimator().setConfig(config_.estimator);
  tf_timeout_s_ = config_.input.tf_timeout_s;
  publishEffectiveConfig(pnh_, config_);
  if (any_change)
    ROS_INFO_STREAM("geofusion: reconfigured; now different from the defaults:\n" << diff);
}

void SceneEstimatorNode::onOdometry(const nav_msgs::OdometryConstPtr& msg) {
  const geometry_msgs::Pose& p = msg->pose.pose;
  const Eigen::Quaterniond q(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z);
  // The same check and unit-quaternion tolerance as every pose that comes in (pose_validation.h).
  if (checkPose(Eigen::Vector3d(p.position.x, p.position.y, p.position.z), q) !=
      PoseStatus::kValid) {
    ROS_WARN_STREAM_THROTTLE(warn_period_s_, "geofusion: odometry on "
                                                 << odom_sub_.getTopic()
                                                 << " with a non-finite position or a "
                                                    "non-unit quaternion ignored");
    return;
  }
  if (msg->header.frame_id != odom_frame_ || msg->child_frame_id.empty()) {
    ROS_WARN_STREAM_THROTTLE(warn_period_s_, "geofusion: odometry on "
                                                 << odom_sub_.getTopic() << " is in frame '"
                                                 << msg->header.frame_id << "' -> '"
                                                 << msg->child_frame_id << "', expected '"
                                                 << odom_frame_ << "' -> the robot base; ignored");
    return;
  }
  if (!last_odom_stamp_.isZero() && msg->header.stamp + ros::Duration(0.5) < last_odom_stamp_) {
    // A looping bag: older odometry would be refused by the buffer as data from the past.
    ROS_WARN_STREAM_THROTTLE(warn_period_s_, "geofusion: odometry time jumped back from "
                                                 << last_odom_stamp_ << " to " << msg->header.stamp
                                                 << ": TF buffer cleared");
    odom_buffer_.clear();
  }
  last_odom_stamp_ = msg->header.stamp;
  odom_base_frame_.set(msg->child_frame_id);
  geometry_msgs::TransformStamped t;
  t.header = msg->header;
  t.child_frame_id = msg->child_frame_id;
  t.transform.translation.x = p.position.x;
  t.transform.translation.y = p.position.y;
  t.transform.translation.z = p.position.z;
  const Eigen::Quaterniond u = q.normalized();
  t.transform.rotation.x = u.x(), t.transform.rotation.y = u.y();
  t.transform.rotation.z = u.z(), t.transform.rotation.w = u.w();
  odom_buffer_.setTransform(t, "odometry " + odom_sub_.getTopic());
}

void SceneEstimatorNode::onTimeJump(const ros::Time& from, const ros::Time& to) {
  ROS_WARN_STREAM("geofusion: time jumped back from " << from << " to " << to
                                                      << " (a looping bag or restarted driver): "
                                                         "the map is reset");
  std::lock_guard<std::mutex> lock(mutex_);
  pipeline_->reset();
  tf_buffer_.clear();
  odom_buffer_.clear();
  last_ = KeyframeResult();
}

bool SceneEstimatorNode::save(const std::string& prefix, std::string* message,
                              std::vector<std::string>* files) {
  RunResults results;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    results.method = method_name_;
    results.source = "scene_estimator_node";
    results.config_yaml = configYaml(config_);
    results.final_map = pipeline_->estimator().numKeyframes() > 0 ? pipeline_->estimator().finish()
                                                                  : KeyframeResult();
    results.trajectory = pipeline_->estimator().trajectory();
    results.trajectory_stamps = pipeline_->estimator().keyframeStamps();
    results.support_plane = pipeline_->estimator().supportPlane();
  }
  const std::string path = prefix + ".yaml";
  std::string error;
  if (!writeRunResults(path, results, &error)) {
    *message = "map not saved: " + error;
    return false;
  }
  files->push_back(path);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (pipeline_->background()) {
      if (!pipeline_->background()->writeBinary(prefix + ".bt", &error)) {
        *message = "objects saved to " + path + " but the background not: " + error;
        return false;
      }
      files->push_back(prefix + ".bt");
    }
  }
  *message = "map saved to " + path + " (" + std::to_string(results.final_map.objects.size()) +
             " objects, " + std::to_string(results.final_map.contacts.size()) + " contacts)";
  return true;
}

bool SceneEstimatorNode::onSave(geofusion::SaveMap::Request& req,
                                geofusion::SaveMap::Response& res) {
  if (req.path.empty()) {
    res.success = false;
    res.message = "empty path";
    return true;
  }
  res.success = save(req.path, &res.message, &res.files);
  return true;
}

bool SceneEstimatorNode::onReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pipeline_->reset();
    last_ = KeyframeResult();
  }
  res.success = true;
  res.message = "map reset";
  std_msgs::Header header;
  header.stamp = ros::Time::now();
  header.frame_id = map_frame_;
  publish(KeyframeResult(), header);
  return true;
}

}  // namespace geofusion
