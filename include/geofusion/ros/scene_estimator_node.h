// The scene estimator on a robot: synchronised RGB-D + detections in (odometry from TF), the
// object map, rviz markers, the trajectory and the map -> odom correction out; services to save
// and reset the map. Run as a nodelet (geofusion/SceneEstimatorNodelet) or as a node
// (scene_estimator_node). Everything but the I/O is EstimatorPipeline, shared with run_offline.
#pragma once

#include "geofusion/config/config.h"
#include "geofusion/ros/estimator_pipeline.h"
#include "geofusion/ros/map_autosaver.h"
#include "geofusion/ros/rgbd_subscriber.h"

#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <geofusion/ExportScene.h>
#include <geofusion/GetSceneGraph.h>
#include <geofusion/LoadMap.h>
#include <geofusion/SaveBopResults.h>
#include <geofusion/SaveMap.h>
#include <geofusion/SceneEstimatorConfig.h>
#include <nav_msgs/Odometry.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>
#include <boost/thread/recursive_mutex.hpp>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace geofusion {

class SceneEstimatorNode {
 public:
  SceneEstimatorNode(ros::NodeHandle nh, ros::NodeHandle pnh);
  ~SceneEstimatorNode();

 private:
  // The constructor's steps, in its order.
  void readParameters();    // frames, configuration, where odometry comes from; throws
  void advertise();         // publishers, services, the background's publication
  void startReconfigure();  // dynamic_reconfigure, from the loaded configuration
  void startOdometry();     // odometry samples on their own queue and thread
  void startAutosave();     // node.autosave_*: where, and the writer
  void loadInitialMap();    // this launch's autosave, else ~initial_map; throws when it cannot
  void startFrames();       // the frame thread and the subscriber
  /// A synchronised set, from the subscriber's callback to the frame thread.
  struct FrameSet {
    sensor_msgs::ImageConstPtr depth;
    sensor_msgs::CameraInfoConstPtr info;
    geofusion::DetectionArrayConstPtr dets;
  };
  void enqueueFrame(FrameSet frame);  // the subscriber's callback: never waits for the estimator
  void processFrames();               // the frame thread
  void takeOverflows();               // queue overflows into the pipeline's drops; mutex_ held
  void onFrame(const sensor_msgs::ImageConstPtr& rgb, const sensor_msgs::ImageConstPtr& depth,
               const sensor_msgs::CameraInfoConstPtr& info,
               const geofusion::DetectionArrayConstPtr& dets);
  void onTimeJump(const ros::Time& from, const ros::Time& to);
  void onOdometry(const nav_msgs::OdometryConstPtr& msg);
  void onTf(const tf2_msgs::TFMessageConstPtr& msg);
  EstimatorPipeline::CameraPose cameraPose(const geofusion::DetectionArray& dets);
  void warnDropped(const sensor_msgs::Image& depth, const geofusion::DetectionArray& dets);
  void reportFailedStages(const KeyframeResult& result);
  void reportRelocalisation(const KeyframeResult& result);
  void publish(const KeyframeResult& result, const std_msgs::Header& header);
  void broadcastCorrection(const ros::Time& stamp);
  void broadcastObjects(const KeyframeResult& result, const std_msgs::Header& header);
  void publishBackground(const BackgroundMap& map, const std_msgs::Header& header);
  void republishObjectFrames();
  bool onSave(geofusion::SaveMap::Request& req, geofusion::SaveMap::Response& res);
  bool onSaveBop(geofusion::SaveBopResults::Request& req, geofusion::SaveBopResults::Response& res);
  bool onReset(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  bool onSceneGraph(geofusion::GetSceneGraph::Request& req,
                    geofusion::GetSceneGraph::Response& res);
  bool onExportScene(geofusion::ExportScene::Request& req, geofusion::ExportScene::Response& res);
  void snapshotMap(KeyframeResult* map, SupportPlane* plane, Eigen::Vector3d* gravity);
  geofusion::SceneGraph sceneGraphOf(const KeyframeResult& map, const SupportPlane& plane,
                                     const Eigen::Vector3d& gravity, const std_msgs::Header& header,
                                     bool check_stability) const;
  void onReconfigure(geofusion::SceneEstimatorConfig& config, uint32_t level);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  void diagnoseAutosave(diagnostic_updater::DiagnosticStatusWrapper& status);
  bool resumeAutosave();  // loads this launch's autosave; false when there is none to resume
  void autosaveIfDue();   // after a keyframe, mutex_ held
  RunResults mapToSave(bool final_solve, const char* source);  // mutex_ held
  bool save(const std::string& prefix, std::string* message, std::vector<std::string>* files);
  bool load(const std::string& path, std::string* message, int* objects);
  bool onLoad(geofusion::LoadMap::Request& req, geofusion::LoadMap::Response& res);

  ros::NodeHandle nh_, pnh_;
  std::string map_frame_, odom_frame_;
  std::atomic<double> tf_timeout_s_{0.1};  // set by reconfigure, read by onFrame
  double warn_period_s_ = 5.0;
  bool publish_tf_ = true;
  std::string save_on_shutdown_;
  // ~launch_id (the launch file's $(anon ...): the same for a respawned node, new for a new
  // launch) is written into every save; an autosave is resumed only by the launch that wrote it.
  std::string launch_id_;
  std::unique_ptr<MapAutosaver> autosaver_;     // null when node.autosave_* are both 0
  std::size_t autosave_failures_reported_ = 0;  // under mutex_
  std::string method_name_;
  GeoFusionConfig config_;  // the effective configuration (reconfigure changes it); under mutex_

  std::mutex mutex_;  // guards the pipeline and the last result
  ModelSet models_;   // the model set (load_map looks classes up in it)
  std::unique_ptr<EstimatorPipeline> pipeline_;
  KeyframeResult last_;
  std::size_t keyframes_ = 0;
  std::size_t failed_stages_ = 0;    // optimisation stages whose result was not used
  std::size_t relocalisations_ = 0;  // keyframes whose camera was relocalised against the map
  // Searches refused, by decision (no_gain, beyond_drift, ambiguous), and objects removed by
  // reason (candidate_timeout, seen_absent, merged), since the start.
  std::map<std::string, std::size_t> relocalisations_refused_, removals_;

  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  ros::Publisher map_pub_, markers_pub_, path_pub_, background_markers_pub_, background_cloud_pub_;
  ros::Publisher background_octomap_pub_;  // advertised only when built with octomap_msgs
  ros::Publisher scene_graph_pub_;
  int background_publish_every_ = 5;
  std::atomic<bool> background_by_height_{true};  // node.background_colour, set by reconfigure
  // The object frames of the last keyframe, re-sent at node.object_frames_rate_hz stamped
  // node.object_frames_tolerance_s ahead of now, so a lookup at the current time succeeds.
  std::mutex object_frames_mutex_;
  std::vector<geometry_msgs::TransformStamped> object_frames_;
  ros::Timer object_frames_timer_;
  double object_frames_tolerance_s_ = 0.2;
  ros::ServiceServer save_srv_, save_bop_srv_, load_srv_, reset_srv_, scene_graph_srv_, export_srv_;
  diagnostic_updater::Updater diagnostics_;
  ros::WallTimer diagnostics_timer_;
  std::atomic<std::size_t> frames_{0};  // synchronised sets received
  // The frame queue (input.frame_queue_size) between the subscriber and the frame thread.
  std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<FrameSet> queue_;
  std::size_t queue_capacity_ = 2;
  bool stop_frames_ = false;
  std::atomic<std::size_t> overflowed_{0};  // pushed out, not yet in the pipeline's drops
  std::thread frame_thread_;
  std::vector<std::size_t> last_counts_;  // input counts at the last diagnostics (rates)
  ros::WallTime last_rates_time_;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<geofusion::SceneEstimatorConfig>> reconfigure_;
  std::unique_ptr<RgbdSubscriber> subscriber_;
  // ~odom_topic: odometry messages go into odom_buffer_ as odom -> base (tf2 interpolates),
  // on their own queue and thread so that a frame waiting for its odometry never blocks their
  // arrival; base -> camera still comes from TF.
  std::string odom_topic_;
  ros::CallbackQueue odom_queue_;
  ros::Subscriber odom_sub_;
  ros::Subscriber tf_sub_;  // stamps of odom -> base on /tf (odometry from TF)
  std::unique_ptr<ros::AsyncSpinner> odom_spinner_;
  ros::Time last_odom_stamp_;  // odometry thread only
  tf2_ros::Buffer odom_buffer_;
  struct Guarded {
    std::string get() const {
      std::lock_guard<std::mutex> lock(m);
      return v;
    }
    void set(const std::string& x) {
      std::lock_guard<std::mutex> lock(m);
      v = x;
    }
    mutable std::mutex m;
    std::string v;
  } odom_base_frame_;  // child_frame_id of the odometry messages
};

}  // namespace geofusion
