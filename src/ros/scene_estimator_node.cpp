#include "geofusion/ros/scene_estimator_node.h"

#include "geofusion/common/atomic_file.h"
#include "geofusion/estimation/bop_results.h"
#include "geofusion/estimation/map_stability.h"
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
#include <cstdlib>
#include <filesystem>

namespace geofusion {

SceneEstimatorNode::SceneEstimatorNode(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh), pnh_(pnh), tf_listener_(tf_buffer_), diagnostics_(nh, pnh) {
  readParameters();
  models_ = loadNodeModelSet(config_);
  const ModelSet& models = models_;
  pipeline_ = std::make_unique<EstimatorPipeline>(
      models, config_.estimator, config_.keyframes, config_.checks,
      config_.background_enabled ? &config_.background : nullptr, config_.ingestion);
  advertise();
  startReconfigure();

  diagnostics_.setHardwareID("geofusion");
  diagnostics_.add("scene estimator", this, &SceneEstimatorNode::diagnose);
  diagnostics_.add("map autosave", this, &SceneEstimatorNode::diagnoseAutosave);
  diagnostics_timer_ = pnh_.createWallTimer(
      ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) { diagnostics_.force_update(); });

  startOdometry();
  startAutosave();
  loadInitialMap();
  startFrames();
  ROS_INFO_STREAM("geofusion: scene estimator (" << method_name_ << ", " << models.size()
                                                 << " classes from " << models.name()
                                                 << ") in frame " << map_frame_);
  publishEffectiveConfig(pnh_, config_);
}

void SceneEstimatorNode::readParameters() {
  pnh_.param<std::string>("map_frame", map_frame_, kMapFrame);
  pnh_.param<std::string>("odom_frame", odom_frame_, kOdomFrame);
  config_ = loadNodeConfig(pnh_, {"odometry", "odom_topic", "initial_map", "launch_id"});
  pnh_.param<std::string>("launch_id", launch_id_, "");
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
  background_by_height_ = config_.node.background_colour == "height";
  object_frames_tolerance_s_ = config_.node.object_frames_tolerance_s;
  method_name_ = toString(config_.estimator.method);
}

void SceneEstimatorNode::advertise() {
  map_pub_ = pnh_.advertise<geofusion::ObjectMap>("object_map", 1, true);
  markers_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("map_markers", 1, true);
  path_pub_ = pnh_.advertise<nav_msgs::Path>("trajectory", 1, true);
  scene_graph_pub_ = pnh_.advertise<geofusion::SceneGraph>("scene_graph", 1, true);
  background_markers_pub_ =
      pnh_.advertise<visualization_msgs::MarkerArray>("background_markers", 1, true);
  background_cloud_pub_ = pnh_.advertise<sensor_msgs::PointCloud2>("background_cloud", 1, true);
#ifdef GEOFUSION_HAVE_OCTOMAP_MSGS
  // Built against octomap_msgs: the tree itself, for octomap_rviz_plugins and OctoMap tools.
  background_octomap_pub_ = pnh_.advertise<octomap_msgs::Octomap>("background_octomap", 1, true);
#endif
  if (BackgroundWorker* background = pipeline_->background()) {
    // Published by the background's thread, every N-th insertion from the first.
    background->setListener([this](const BackgroundMap& map, double stamp_s, std::size_t n) {
      if ((n - 1) % static_cast<std::size_t>(background_publish_every_) != 0) return;
      std_msgs::Header header;
      header.stamp = ros::Time(stamp_s);
      header.frame_id = map_frame_;
      publishBackground(map, header);
    });
  }
  if (config_.node.publish_object_frames && config_.node.object_frames_rate_hz > 0) {
    object_frames_timer_ =
        nh_.createTimer(ros::Duration(1.0 / config_.node.object_frames_rate_hz),
                        [this](const ros::TimerEvent&) { republishObjectFrames(); });
  }
  save_srv_ = pnh_.advertiseService("save_map", &SceneEstimatorNode::onSave, this);
  save_bop_srv_ = pnh_.advertiseService("save_bop_results", &SceneEstimatorNode::onSaveBop, this);
  load_srv_ = pnh_.advertiseService("load_map", &SceneEstimatorNode::onLoad, this);
  reset_srv_ = pnh_.advertiseService("reset", &SceneEstimatorNode::onReset, this);
  scene_graph_srv_ = pnh_.advertiseService("scene_graph", &SceneEstimatorNode::onSceneGraph, this);
  export_srv_ = pnh_.advertiseService("export_scene", &SceneEstimatorNode::onExportScene, this);
}

void SceneEstimatorNode::startReconfigure() {
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
}

void SceneEstimatorNode::startOdometry() {
  // Odometry samples on their own queue and thread, so that a frame waiting for its pose never
  // blocks their arrival.
  ros::NodeHandle odom_nh(nh_);
  odom_nh.setCallbackQueue(&odom_queue_);
  if (odom_topic_.empty()) tf_sub_ = odom_nh.subscribe("/tf", 200, &SceneEstimatorNode::onTf, this);
  odom_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &odom_queue_);
  odom_spinner_->start();
  if (!odom_topic_.empty()) {
    odom_sub_ = odom_nh.subscribe(odom_topic_, 200, &SceneEstimatorNode::onOdometry, this);
    ROS_INFO_STREAM("geofusion: odometry from " << odom_sub_.getTopic()
                                                << " (nav_msgs/Odometry) instead of TF's "
                                                << odom_frame_ << " -> base");
  }
}

// node.autosave_*: the prefix ("" : $ROS_HOME/geofusion/<node namespace>/autosave), its folder
// made now; a folder that cannot be made is reported here and by every failed autosave.
void SceneEstimatorNode::startAutosave() {
  MapAutosaver::Config c;
  c.every_keyframes = config_.node.autosave_every_keyframes;
  c.every_s = config_.node.autosave_every_s;
  c.prefix = config_.node.autosave_prefix;
  if (!c.enabled()) {
    ROS_INFO("geofusion: autosave off (node.autosave_every_keyframes and _every_s are 0)");
    return;
  }
  if (c.prefix.empty()) {
    const char* ros_home = std::getenv("ROS_HOME");
    const char* home = std::getenv("HOME");
    std::string node = pnh_.getNamespace();
    std::replace(node.begin(), node.end(), '/', '_');
    c.prefix = (ros_home ? std::string(ros_home) : std::string(home ? home : ".") + "/.ros") +
               "/geofusion/" + node.substr(node.find_first_not_of('_')) + "/autosave";
  }
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(c.prefix).parent_path(), ec);
  if (ec)
    ROS_ERROR_STREAM("geofusion: autosave folder of " << c.prefix
                                                      << " cannot be made: " << ec.message());
  autosaver_ = std::make_unique<MapAutosaver>(
      c, [this](const std::string& prefix, RunResults map, MapFiles* files, std::string* error) {
        return pipeline_->saveMap(prefix, std::move(map), files, error);
      });
  ROS_INFO_STREAM("geofusion: autosave every " << c.every_keyframes << " keyframes or " << c.every_s
                                               << " s to " << c.prefix << ".yaml");
}

// The autosave this launch wrote (same ~launch_id: the node was respawned) is continued; one
// from another launch, or from a node started without ~launch_id, is left alone (it is
// overwritten by the first autosave).
bool SceneEstimatorNode::resumeAutosave() {
  if (!autosaver_ || !config_.node.resume_autosave) return false;
  const std::string& prefix = autosaver_->config().prefix;
  std::string session, error, message;
  switch (autosaveResume(prefix, launch_id_, &session, &error)) {
    case AutosaveResume::kNone: return false;
    case AutosaveResume::kUnreadable:
      ROS_ERROR_STREAM("geofusion: autosave not resumed: " << error);
      return false;
    case AutosaveResume::kOtherLaunch:
      ROS_INFO_STREAM("geofusion: the autosave " << prefix << ".yaml is from another launch ("
                                                 << (session.empty() ? "unknown" : session)
                                                 << "): not resumed, it will be overwritten");
      return false;
    case AutosaveResume::kResume: break;
  }
  int objects = 0;
  if (!load(prefix, &message, &objects)) {
    ROS_ERROR_STREAM("geofusion: this launch's autosave not resumed: " << message);
    return false;
  }
  ROS_WARN_STREAM("geofusion: resumed after a restart: " << message);
  return true;
}

void SceneEstimatorNode::loadInitialMap() {
  if (resumeAutosave()) return;
  // ~initial_map: continue a saved map after a restart; one that cannot be loaded stops the
  // start (a robot must not silently begin from nothing when told to resume).
  std::string initial_map;
  pnh_.param<std::string>("initial_map", initial_map, "");
  if (!initial_map.empty()) {
    std::string message;
    int objects = 0;
    if (!load(initial_map, &message, &objects))
      throw std::runtime_error("~initial_map: " + message + "; not starting");
    ROS_INFO_STREAM("geofusion: " << message);
  }
}

void SceneEstimatorNode::startFrames() {
  const RgbdSubscriber::Config sub = RgbdSubscriber::configOf(pnh_, config_.input);
  queue_capacity_ = static_cast<std::size_t>(std::max(1, config_.input.frame_queue_size));
  frame_thread_ = std::thread([this] { processFrames(); });
  subscriber_ = std::make_unique<RgbdSubscriber>(
      nh_, sub,
      [this](const auto& /*rgb*/, const auto& depth, const auto& info, const auto& dets) {
        enqueueFrame({depth, info, dets});
      },
      [this](const ros::Time& from, const ros::Time& to) { onTimeJump(from, to); });
}

SceneEstimatorNode::~SceneEstimatorNode() {
  diagnostics_timer_.stop();  // its callbacks read the autosaver, reset below
  // The frame thread first: it reads the subscriber (newestStamp). Resetting the subscriber
  // before the join was a use-after-free window at unload (ThreadSanitizer, 2026-12-05).
  // Frames the subscriber still hands over meanwhile wait in the queue, unprocessed.
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    stop_frames_ = true;
  }
  queue_cv_.notify_all();
  if (frame_thread_.joinable()) frame_thread_.join();
  subscriber_.reset();
  object_frames_timer_.stop();
  // No background publication in flight once this returns (the listener runs under its lock).
  if (pipeline_ && pipeline_->background()) pipeline_->background()->setListener(nullptr);
  if (odom_spinner_) odom_spinner_->stop();
  odom_sub_.shutdown();
  tf_sub_.shutdown();
  autosaver_.reset();  // writes a snapshot still waiting; it saves through pipeline_
  if (!save_on_shutdown_.empty()) {
    std::string message;
    std::vector<std::string> files;
    save(save_on_shutdown_, &message, &files);
    ROS_INFO_STREAM("geofusion: " << message);
  }
}

// The subscriber's callback hands the set over and returns: a slow keyframe never backs up
// roscpp's queues (whose overflows nobody would count). When frames come faster than they are
// processed, the oldest waiting one goes, counted as a queue overflow.
void SceneEstimatorNode::enqueueFrame(FrameSet frame) {
  ++frames_;
  bool overflow = false;
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    queue_.push_back(std::move(frame));
    if (queue_.size() > queue_capacity_) {
      queue_.pop_front();
      overflow = true;
    }
  }
  queue_cv_.notify_one();
  if (overflow) {
    ++overflowed_;
    ROS_WARN_STREAM_THROTTLE(warn_period_s_,
                             "geofusion: frames come faster than the estimator takes them: the "
                             "oldest waiting frame is dropped (input.frame_queue_size "
                                 << queue_capacity_ << ")");
  }
}

void SceneEstimatorNode::processFrames() {
  for (;;) {
    FrameSet frame;
    {
      std::unique_lock<std::mutex> lock(queue_mutex_);
      queue_cv_.wait(lock, [this] { return stop_frames_ || !queue_.empty(); });
      if (stop_frames_) return;
      frame = std::move(queue_.front());
      queue_.pop_front();
    }
    onFrame(nullptr, frame.depth, frame.info, frame.dets);
  }
}

void SceneEstimatorNode::takeOverflows() {
  if (const std::size_t n = overflowed_.exchange(0))
    pipeline_->countDropped(FrameDrop::kQueueOverflow, n);
}

void SceneEstimatorNode::onFrame(const sensor_msgs::ImageConstPtr& /*rgb*/,
                                 const sensor_msgs::ImageConstPtr& depth,
                                 const sensor_msgs::CameraInfoConstPtr& info,
                                 const geofusion::DetectionArrayConstPtr& dets) {
  const EstimatorPipeline::CameraPose pose = cameraPose(*dets);
  KeyframeResult result;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    takeOverflows();
    const auto outcome =
        pipeline_->process(*depth, *info, *dets, pose, subscriber_->newestStamp(), &result);
    if (outcome == EstimatorPipeline::Outcome::kDropped) {
      warnDropped(*depth, *dets);
      return;
    }
    if (outcome != EstimatorPipeline::Outcome::kKeyframe) return;
    ++keyframes_;
    last_ = result;
    autosaveIfDue();
    reportFailedStages(result);
    reportRelocalisation(result);
    if (!result.detection_warning.empty())
      ROS_WARN_STREAM_THROTTLE(10.0, "geofusion: " << result.detection_warning);
    if (pipeline_->lastCapped() > 0)
      ROS_WARN_STREAM_THROTTLE(
          warn_period_s_, "geofusion: " << pipeline_->lastCapped()
                                        << " detections beyond input.max_detections_per_frame ("
                                        << config_.checks.max_detections
                                        << ") dropped, the lowest scores first");
    if (pipeline_->lastKeyframeOverran())
      ROS_WARN_STREAM_THROTTLE(warn_period_s_,
                               "geofusion: keyframe "
                                   << result.keyframe << " took " << pipeline_->lastKeyframeMs()
                                   << " ms, over input.keyframe_budget_ms ("
                                   << pipeline_->ingestionConfig().keyframe_budget_ms << "; "
                                   << pipeline_->budgetOverruns() << " overruns so far)");
  }
  std_msgs::Header header;
  header.stamp = dets->header.stamp;
  header.frame_id = map_frame_;
  publish(result, header);
  ROS_DEBUG_STREAM("geofusion: keyframe " << result.keyframe << ": " << result.objects.size()
                                          << " objects, " << result.timings.total_ms << " ms");
}

// The camera pose at the detections' stamp: odom -> camera from TF, or odom -> base from the
// odometry topic and base -> camera from TF.
EstimatorPipeline::CameraPose SceneEstimatorNode::cameraPose(
    const geofusion::DetectionArray& dets) {
  EstimatorPipeline::CameraPose pose;
  if (odom_topic_.empty()) {
    pose.found =
        lookupTransformWallTimeout(tf_buffer_, odom_frame_, dets.header.frame_id, dets.header.stamp,
                                   tf_timeout_s_, &pose.T_odom_cam, &pose.error);
    return pose;
  }
  // Its own buffer, so a recording's odom -> base on TF cannot mix in.
  Eigen::Isometry3d T_odom_base, T_base_cam;
  const std::string base = odom_base_frame_.get();
  pose.found = !base.empty() &&
               lookupTransformWallTimeout(odom_buffer_, odom_frame_, base, dets.header.stamp,
                                          tf_timeout_s_, &T_odom_base, &pose.error) &&
               lookupTransformWallTimeout(tf_buffer_, base, dets.header.frame_id, dets.header.stamp,
                                          tf_timeout_s_, &T_base_cam, &pose.error);
  if (base.empty()) pose.error = "no odometry received on " + odom_sub_.getTopic() + " yet";
  pose.T_odom_cam = T_odom_base * T_base_cam;
  return pose;
}

// A throttled warning per drop reason, with what to check. Under mutex_.
void SceneEstimatorNode::warnDropped(const sensor_msgs::Image& depth,
                                     const geofusion::DetectionArray& dets) {
  const FrameDrop reason = pipeline_->lastDrop();
  const std::size_t so_far = pipeline_->drops().of(reason);
  switch (reason) {
    case FrameDrop::kNoOdometry:
      ROS_WARN_STREAM_THROTTLE(warn_period_s_, "geofusion: frame skipped, no TF from "
                                                   << odom_frame_ << " to " << dets.header.frame_id
                                                   << ": " << pipeline_->lastPoseError() << " ("
                                                   << so_far << " so far)");
      break;
    case FrameDrop::kOdometryGap:
      ROS_WARN_STREAM_THROTTLE(warn_period_s_,
                               "geofusion: frame at "
                                   << dets.header.stamp << " skipped: its odometry samples are "
                                   << pipeline_->odometry().gapAround(dets.header.stamp.toSec())
                                   << " s apart, more than input.max_odometry_gap_s ("
                                   << pipeline_->ingestionConfig().max_odometry_gap_s
                                   << "); its pose would be a guess (" << so_far << " so far)");
      break;
    case FrameDrop::kBadDepth:
      ROS_WARN_STREAM_THROTTLE(
          warn_period_s_,
          "geofusion: frame skipped: "
              << (depthProblem(depth) ? depthProblem(depth) : "camera_info or depth size mismatch")
              << " (" << so_far << " so far)");
      break;
    case FrameDrop::kBadCameraInfo:
      ROS_WARN_STREAM_THROTTLE(warn_period_s_,
                               "geofusion: frame skipped: " << pipeline_->lastCameraError() << " ("
                                                            << so_far << " so far)");
      break;
    default:
      ROS_WARN_STREAM_THROTTLE(warn_period_s_,
                               "geofusion: frame at "
                                   << dets.header.stamp << " skipped: " << toString(reason) << " ("
                                   << so_far << " so far; input.max_frame_age_s "
                                   << pipeline_->ingestionConfig().max_frame_age_s << ")");
  }
}

// Stamps of odom -> * transforms on /tf: the odometry samples that tell a gap.
void SceneEstimatorNode::onTf(const tf2_msgs::TFMessageConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const geometry_msgs::TransformStamped& t : msg->transforms)
    if (t.header.frame_id == odom_frame_) pipeline_->odometry().add(t.header.stamp.toSec());
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

// A relocalisation (map -> odom jumps by its correction) is said and counted for diagnostics.
void SceneEstimatorNode::reportRelocalisation(const KeyframeResult& result) {
  for (const Removal& removal : result.removals) ++removals_[toString(removal.reason)];
  const Relocalisation& r = result.relocalisation;
  if (r.tried && !r.applied) {
    ++relocalisations_refused_[toString(r.decision)];
    ROS_DEBUG_STREAM("geofusion: keyframe " << result.keyframe << " relocalisation refused ("
                                            << toString(r.decision) << "): support "
                                            << r.inliers_after << ", runner-up " << r.runner_up
                                            << ", Mahalanobis^2 " << r.mahalanobis_sq);
  }
  if (!r.applied) return;
  ++relocalisations_;
  ROS_INFO_STREAM("geofusion: keyframe "
                  << result.keyframe << " relocalised against the map: " << r.inliers_after
                  << " detections on mapped objects (" << r.inliers_before
                  << " before), map -> odom corrected by "
                  << 100.0 * r.T_correction.translation().norm() << " cm, "
                  << Eigen::AngleAxisd(r.T_correction.linear()).angle() * 180.0 / M_PI << " deg");
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
  // The plan after every keyframe, without the stability check (0.2 s of Bullet for 19 YCB
  // objects: the service runs it on demand; docs/scene_graph.md).
  scene_graph_pub_.publish(sceneGraphOf(result, plane, gravity, header, false));
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
  broadcastObjects(result, header);
}

// Called with the background's map locked, on the background's thread after an insertion (or
// on a reset): never takes mutex_, so the estimator's thread never waits for it.
void SceneEstimatorNode::publishBackground(const BackgroundMap& map,
                                           const std_msgs::Header& header) {
  const std::vector<Eigen::Vector3d> centres = map.occupiedCentres();
  const double resolution = map.config().resolution_m;
  std::string octree;  // binary serialisation, only with octomap_msgs
  if (background_octomap_pub_ && background_octomap_pub_.getNumSubscribers() > 0)
    octree = map.binaryData();
  background_markers_pub_.publish(
      backgroundMarkers(centres, resolution, header, background_by_height_.load()));
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

// Every object of the map as a TF frame under the map frame (the same ids as ObjectMap's
// objects); removed objects are no longer sent, so their frames age out of TF buffers.
void SceneEstimatorNode::broadcastObjects(const KeyframeResult& result,
                                          const std_msgs::Header& header) {
  if (!config_.node.publish_object_frames) return;
  std::vector<geometry_msgs::TransformStamped> frames;
  for (const ObjectEstimate& o : result.objects) {
    geometry_msgs::TransformStamped t = tf2::eigenToTransform(o.T_map_obj);
    t.header = header;
    t.child_frame_id = config_.node.object_frame_prefix + std::to_string(messageId(o.id));
    frames.push_back(t);
  }
  {
    std::lock_guard<std::mutex> lock(object_frames_mutex_);
    object_frames_ = frames;
  }
  if (!frames.empty()) tf_broadcaster_.sendTransform(frames);
}

// The last keyframe's object frames again, stamped ahead of now by node.object_frames_tolerance_s
// (as amcl's transform_tolerance post-dates map -> odom): a lookup at ros::Time::now() works
// between keyframes. A removed object's frame is not sent after the keyframe that removed it;
// the last re-send before it reaches tolerance_s past that (TF cannot take a frame back).
void SceneEstimatorNode::republishObjectFrames() {
  std::vector<geometry_msgs::TransformStamped> frames;
  {
    std::lock_guard<std::mutex> lock(object_frames_mutex_);
    frames = object_frames_;
  }
  if (frames.empty()) return;
  const ros::Time stamp = ros::Time::now() + ros::Duration(object_frames_tolerance_s_);
  for (auto& t : frames) t.header.stamp = stamp;
  tf_broadcaster_.sendTransform(frames);
}

void SceneEstimatorNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  takeOverflows();
  const StageTimings& t = last_.timings;
  if (frames_ == 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no synchronised input yet");
  } else if (last_.stage_one.failed() || last_.stage_two.failed()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "the last keyframe's optimisation failed; its result is not used");
  } else if (!last_.detection_warning.empty()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, last_.detection_warning);
  } else if (pipeline_->lastKeyframeOverran()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "the last keyframe took longer than input.keyframe_budget_ms");
  } else if (pipeline_->lastCapped() > 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "the last frame had more detections than input.max_detections_per_frame");
  } else if (pipeline_->drops().total() > frames_ / 2) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "most frames dropped: " + pipeline_->drops().summary());
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
  status.add("synchronised frames", frames_.load());
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
    status.add("synchronised by the subscriber", synced);
    pipeline_->setUnsynchronised(unsynchronisedFrames(counts, synced));
    last_counts_ = counts;
    last_rates_time_ = now;
  }
  status.add("keyframes", keyframes_);
  status.add("frames dropped", pipeline_->drops().summary());
  for (std::size_t i = 1; i < static_cast<std::size_t>(FrameDrop::kCount); ++i)
    status.add("frames dropped: " + std::string(toString(static_cast<FrameDrop>(i))),
               pipeline_->drops().count[i]);
  status.add("keyframes over the time budget", pipeline_->budgetOverruns());
  status.add("detections", pipeline_->tally().summary());
  status.add("objects", last_.objects.size());
  status.add("contacts", last_.contacts.size());
  status.add("last keyframe: stage I", toString(last_.stage_one.status));
  status.add("last keyframe: stage II", toString(last_.stage_two.status));
  status.add("failed optimisation stages", failed_stages_);
  status.add("relocalisations", relocalisations_);
  for (const char* d : {"no_gain", "beyond_drift", "ambiguous"}) {
    const auto it = relocalisations_refused_.find(d);
    status.add(std::string("relocalisations refused: ") + d,
               it == relocalisations_refused_.end() ? 0 : it->second);
  }
  for (const char* reason : {"candidate_timeout", "seen_absent", "merged"}) {
    const auto it = removals_.find(reason);
    status.add(std::string("objects removed: ") + reason, it == removals_.end() ? 0 : it->second);
  }
  status.add("last keyframe ms: consistency", t.consistency_ms);
  status.add("last keyframe ms: association", t.association_ms);
  status.add("last keyframe ms: lifecycle", t.lifecycle_ms);
  status.add("last keyframe ms: stage I", t.stage_one_ms);
  status.add("last keyframe ms: relations", t.relations_ms);
  status.add("last keyframe ms: stage II", t.stage_two_ms);
  status.add("last keyframe ms: total", t.total_ms);
  if (BackgroundWorker* background = pipeline_->background()) {
    const BackgroundStats b = background->stats();
    status.add("background ms: last insertion", b.last_ms);
    status.add("background ms: p95 insertion", b.p95_ms);
    status.add("background ms: a keyframe (amortised)", b.amortisedMs());
    status.add("background keyframes inserted", b.inserted);
    status.add("background keyframes skipped (busy)", b.skipped);
    status.add("background keyframes passed over (camera still)", b.still);
  }
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
  background_by_height_ = config_.node.background_colour == "height";
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
  std::lock_guard<std::mutex> lock(mutex_);
  pipeline_->odometry().add(msg->header.stamp.toSec());
}

// A snapshot of the map (no solve: cheap) for the autosave's writer, when one is due.
void SceneEstimatorNode::autosaveIfDue() {
  if (!autosaver_) return;
  const MapAutosaver::Status s = autosaver_->status();
  if (s.failed > autosave_failures_reported_) {
    autosave_failures_reported_ = s.failed;
    ROS_WARN_STREAM_THROTTLE(warn_period_s_, "geofusion: autosave to "
                                                 << autosaver_->config().prefix << " failed ("
                                                 << s.failed << " so far): " << s.last_error
                                                 << "; mapping goes on, the previous autosave "
                                                    "is whole");
  }
  const double now_s = ros::WallTime::now().toSec();
  if (!autosaver_->keyframeAdded(now_s)) return;
  autosaver_->offer(mapToSave(false, "scene_estimator_node autosave"), now_s);
}

// The map as ~save_map and the autosave write it: what the run was, who saved it. mutex_ held.
RunResults SceneEstimatorNode::mapToSave(bool final_solve, const char* source) {
  RunResults map = pipeline_->currentMap(final_solve);
  map.method = method_name_;
  map.source = source;
  map.model_set = config_.model_set.name;
  map.config_yaml = configYaml(config_);
  map.session = launch_id_;
  return map;
}

void SceneEstimatorNode::diagnoseAutosave(diagnostic_updater::DiagnosticStatusWrapper& status) {
  if (!autosaver_) {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "off");
    return;
  }
  const MapAutosaver::Status s = autosaver_->status();
  if (!s.last_error.empty())
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "the last autosave failed (mapping goes on, the previous autosave is whole): " +
                       s.last_error);
  else if (s.saved == 0)
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "no autosave yet");
  else
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "saved");
  status.add("prefix", autosaver_->config().prefix);
  status.add("autosaves", s.saved);
  status.add("failed autosaves", s.failed);
  status.add("keyframes in the last autosave", s.last_keyframes);
  if (s.last_saved_s >= 0.0)
    status.addf("seconds since the last autosave", "%.1f",
                ros::WallTime::now().toSec() - s.last_saved_s);
  status.add("launch id", launch_id_);
}

void SceneEstimatorNode::onTimeJump(const ros::Time& from, const ros::Time& to) {
  ROS_WARN_STREAM("geofusion: time jumped back from " << from << " to " << to
                                                      << " (a looping bag or restarted driver): "
                                                         "the map is reset");
  {
    // Frames from before the jump would look newer than everything after it.
    std::lock_guard<std::mutex> lock(queue_mutex_);
    queue_.clear();
  }
  std::lock_guard<std::mutex> lock(mutex_);
  overflowed_ = 0;
  pipeline_->reset();
  // Where the clock went back too (simulated time, a looping bag), tf2's listener clears its
  // buffer at its first message after the jump; clearing it here again would drop the new
  // loop's first transforms, received before this frame (its first keyframe lost for "no camera
  // pose"). Stamps that go back while the clock does not would be refused as old data: cleared.
  // The odometry's own buffer is cleared by its callback when its stamps go back.
  if (ros::Time::now() >= to + ros::Duration(0.5 * (from - to).toSec())) tf_buffer_.clear();
  last_ = KeyframeResult();
}

bool SceneEstimatorNode::save(const std::string& prefix, std::string* message,
                              std::vector<std::string>* files) {
  std::lock_guard<std::mutex> lock(mutex_);
  takeOverflows();
  RunResults map = mapToSave(true, "scene_estimator_node");
  const std::size_t objects = map.final_map.objects.size(),
                    contacts = map.final_map.contacts.size();
  MapFiles written;
  std::string error;
  if (!pipeline_->saveMap(prefix, std::move(map), &written, &error)) {
    *message = "map not saved: " + error + " (the previous map under " + prefix +
               ", if any, is untouched)";
    return false;
  }
  files->push_back(written.yaml);
  if (!written.background.empty()) files->push_back(written.background);
  *message = "map saved to " + written.yaml + " (" + std::to_string(objects) + " objects, " +
             std::to_string(contacts) + " contacts" +
             (written.background.empty() ? "" : ", background " + written.background) + ")";
  return true;
}

bool SceneEstimatorNode::load(const std::string& path, std::string* message, int* objects) {
  RunResults loaded;
  std::string error;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!pipeline_->loadMap(path, models_, &loaded, &error)) {
      *message = "map not loaded: " + error;
      return false;
    }
    last_ = loaded.final_map;
  }
  *objects = static_cast<int>(loaded.final_map.objects.size());
  *message = "map loaded from " + path + " (" + std::to_string(*objects) + " objects, " +
             std::to_string(loaded.final_map.contacts.size()) + " contacts, map id " +
             loaded.map_id + ")";
  std_msgs::Header header;
  header.stamp = ros::Time::now();
  header.frame_id = map_frame_;
  publish(loaded.final_map, header);
  return true;
}

bool SceneEstimatorNode::onLoad(geofusion::LoadMap::Request& req,
                                geofusion::LoadMap::Response& res) {
  res.success = load(req.path, &res.message, &res.objects);
  if (res.success)
    ROS_INFO_STREAM("geofusion: " << res.message);
  else
    ROS_WARN_STREAM("geofusion: " << res.message);
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

// The map's support graph as a plan; with `check_stability`, each object's stability checked on
// the map's support plane (else STABILITY_UNKNOWN).
geofusion::SceneGraph SceneEstimatorNode::sceneGraphOf(const KeyframeResult& map,
                                                       const SupportPlane& plane,
                                                       const Eigen::Vector3d& gravity,
                                                       const std_msgs::Header& header,
                                                       bool check_stability) const {
  physics::StabilityResult stability;
  if (check_stability) {
    stability = checkMapStability(map.objects, &plane, gravity, config_.estimator.physics);
    for (const std::string& w : stability.warnings)
      ROS_WARN_STREAM_THROTTLE(warn_period_s_, "geofusion: scene graph: stability: " << w);
  }
  const SupportGraph graph =
      mapSupportGraph(map.objects, map.contacts, gravity, check_stability ? &stability : nullptr,
                      config_.scene_graph);
  for (const std::string& w : graph.warnings)
    ROS_WARN_STREAM_THROTTLE(warn_period_s_, "geofusion: scene graph: " << w);
  return toSceneGraphMsg(graph, header);
}

// The current map, its support plane and gravity, copied under the lock (the services' input).
void SceneEstimatorNode::snapshotMap(KeyframeResult* map, SupportPlane* plane,
                                     Eigen::Vector3d* gravity) {
  std::lock_guard<std::mutex> lock(mutex_);
  *map = pipeline_->currentMap(false).final_map;
  *plane = pipeline_->estimator().supportPlane();
  *gravity = pipeline_->estimator().config().gravity;
}

// ~scene_graph: the current map's plan, made now.
bool SceneEstimatorNode::onSceneGraph(geofusion::GetSceneGraph::Request& /*req*/,
                                      geofusion::GetSceneGraph::Response& res) {
  KeyframeResult map;
  SupportPlane plane;
  Eigen::Vector3d gravity;
  snapshotMap(&map, &plane, &gravity);
  std_msgs::Header header;
  header.frame_id = map_frame_;
  header.stamp = ros::Time(std::max(0.0, map.stamp_s));
  res.graph = sceneGraphOf(map, plane, gravity, header, true);
  return true;
}

// ~export_scene: the current map written for simulators (docs/scene_export.md).
bool SceneEstimatorNode::onExportScene(geofusion::ExportScene::Request& req,
                                       geofusion::ExportScene::Response& res) {
  if (req.folder.empty()) {
    res.success = false;
    res.message = "empty folder";
    return true;
  }
  KeyframeResult map;
  SupportPlane plane;
  Eigen::Vector3d gravity;
  snapshotMap(&map, &plane, &gravity);
  // Named with the ids of the node's messages (ObjectMap, ~scene_graph: messageId).
  for (ObjectEstimate& o : map.objects) o.id = static_cast<int>(messageId(o.id));
  physics::SceneExport exported;
  std::string error;
  res.success = exportMapScene(map.objects, &plane, gravity, config_.estimator.physics, req.folder,
                               &exported, &error);
  if (!res.success) {
    res.message = "export_scene: " + error;
    ROS_WARN_STREAM("geofusion: " << res.message);
    return true;
  }
  res.files = {exported.sdf_path, exported.urdf_path};
  res.files.insert(res.files.end(), exported.mesh_paths.begin(), exported.mesh_paths.end());
  res.warnings = exported.warnings;
  for (const std::string& w : exported.warnings) ROS_WARN_STREAM("geofusion: export_scene: " << w);
  res.message = "exported " + std::to_string(exported.exported) + " of " +
                std::to_string(map.objects.size()) + " objects to " + exported.sdf_path + " and " +
                exported.urdf_path;
  ROS_INFO_STREAM("geofusion: " << res.message);
  return true;
}

// The current map as BOP results, seen from every keyframe (bop_results.h, finalMapImages).
bool SceneEstimatorNode::onSaveBop(geofusion::SaveBopResults::Request& req,
                                   geofusion::SaveBopResults::Response& res) {
  if (req.path.empty()) {
    res.success = false;
    res.message = "empty path";
    return true;
  }
  std::string csv;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const RunResults map = pipeline_->currentMap();
    if (map.trajectory.empty()) {
      res.success = false;
      res.message = "no keyframe yet: nothing to write";
      return true;
    }
    BopIds ids;
    ids.scene_id = req.scene_id;
    const std::vector<BopImage> images = finalMapImages(map);
    csv = bopResultsCsv(images, pipeline_->intrinsics(), ids);
    res.images = static_cast<int>(images.size());
  }
  std::string error;
  res.success = writeTextAtomically(req.path, csv, &error);
  res.rows = static_cast<int>(std::count(csv.begin(), csv.end(), '\n')) - 1;
  res.message = res.success
                    ? "BOP results written to " + req.path + " (" + std::to_string(res.rows) +
                          " rows, " + std::to_string(res.images) + " images)"
                    : "BOP results not written: " + error;
  if (!res.success) ROS_WARN_STREAM("geofusion: " << res.message);
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
  if (BackgroundWorker* background = pipeline_->background())  // the emptied background
    background->withMap([&](const BackgroundMap& map) { publishBackground(map, header); });
  return true;
}

}  // namespace geofusion
