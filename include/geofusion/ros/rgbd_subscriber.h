// The one input path of every node: synchronised RGB image + depth image + camera_info, and
// detections when the node wants them (approximate time). It watches its inputs and warns, naming
// the topics, when one stops arriving, never arrives or when they never synchronise; and it
// notices time jumping backwards (a looping bag), warns and restarts synchronisation. The
// estimator and the detection viewer take detections; the visual odometry takes RGB-D alone.
#pragma once

#include "geofusion/common/input_monitor.h"
#include "geofusion/common/robot_names.h"
#include "geofusion/common/time_jump.h"
#include "geofusion/config/config.h"

#include <geofusion/DetectionArray.h>
#include <image_transport/image_transport.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/synchronizer.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace geofusion {

class RgbdSubscriber {
 public:
  struct Config {
    /// Topic names, resolved in the node's namespace; remap them or set these parameters.
    std::string rgb_topic = "head_camera/rgb/image_raw";
    std::string depth_topic = "head_camera/depth_registered/image_raw";
    std::string camera_info_topic = "head_camera/rgb/camera_info";
    std::string detections_topic = "detections";
    /// Queue of each synchroniser input.
    int queue_size = 10;
    /// Largest stamp spread of a synchronised set, seconds.
    double max_interval_s = 0.05;
    /// Stamp decrease that counts as a jump back in time (looping bag, restarted driver), seconds.
    double time_jump_tolerance_s = 1.0;
    /// Period of the watchdog check and of its (throttled) warnings, seconds.
    double warn_period_s = 5.0;
    InputMonitor::Config monitor;
  };

  /// The config of a node: topic names from its private parameters (rgb_topic, depth_topic,
  /// camera_info_topic, and detections_topic unless `with_detections` is false: the robot file),
  /// queue, synchronisation and watchdog from the configuration's input section.
  static Config configOf(const ros::NodeHandle& pnh, const InputConfig& input,
                         bool with_detections = true);

  using FrameCallback = std::function<void(
      const sensor_msgs::ImageConstPtr& rgb, const sensor_msgs::ImageConstPtr& depth,
      const sensor_msgs::CameraInfoConstPtr& info, const geofusion::DetectionArrayConstPtr& dets)>;
  using TimeJumpCallback = std::function<void(const ros::Time& from, const ros::Time& to)>;

  RgbdSubscriber(ros::NodeHandle nh, const Config& config, FrameCallback on_frame,
                 TimeJumpCallback on_time_jump = nullptr);
  ~RgbdSubscriber();

  bool withDetections() const { return !config_.detections_topic.empty(); }
  /// The resolved topic names, in the order rgb, depth, camera_info (, detections).
  std::vector<std::string> topics() const;
  std::size_t synchronizedCount() const;
  /// Messages received on each input (order of topics()) since the last reset or time jump.
  std::vector<std::size_t> messageCounts() const;

  /// The synchroniser of RGB, depth, camera_info and detections (approximate time, the queue and
  /// stamp spread of `config`): the node's, and run_offline's over a bag, so that both make the
  /// same sets of the same messages.
  using DetectionPolicy = message_filters::sync_policies::ApproximateTime<
      sensor_msgs::Image, sensor_msgs::Image, sensor_msgs::CameraInfo, geofusion::DetectionArray>;
  using DetectionSync = message_filters::Synchronizer<DetectionPolicy>;
  static std::unique_ptr<DetectionSync> makeDetectionSync(const Config& config);

  /// The newest header stamp received on any input (since the last time jump), seconds.
  double newestStamp() const;

 private:
  using RgbdPolicy =
      message_filters::sync_policies::ApproximateTime<sensor_msgs::Image, sensor_msgs::Image,
                                                      sensor_msgs::CameraInfo>;
  using RgbdSync = message_filters::Synchronizer<RgbdPolicy>;

  void makeSynchronizer();
  /// Counts the message and passes it through the time-jump gate: false when it is to be
  /// dropped (from before a jump); a jump restarts the synchroniser and calls on_time_jump_.
  bool noteInput(std::size_t index, const ros::Time& stamp);
  template <int I, class M>
  void onInput(const boost::shared_ptr<M const>& msg);
  void onSynchronized(const sensor_msgs::ImageConstPtr& rgb,
                      const sensor_msgs::ImageConstPtr& depth,
                      const sensor_msgs::CameraInfoConstPtr& info,
                      const geofusion::DetectionArrayConstPtr& dets);
  void onWatchdog(const ros::WallTimerEvent&);

  ros::NodeHandle nh_;
  Config config_;
  FrameCallback on_frame_;
  TimeJumpCallback on_time_jump_;
  image_transport::ImageTransport it_;
  image_transport::Subscriber rgb_sub_;
  image_transport::Subscriber depth_sub_;
  ros::Subscriber info_sub_;
  ros::Subscriber detections_sub_;
  // The synchroniser is fed by hand (Synchronizer::add) rather than connected to the
  // subscribers, so that it can be replaced after a time jump without touching a filter chain
  // from inside its own callback. sync_mutex_ serialises feeding, replacing and the frame
  // callback (which runs inside add()).
  std::mutex sync_mutex_;
  std::unique_ptr<RgbdSync> rgbd_sync_;            // without detections
  std::unique_ptr<DetectionSync> detection_sync_;  // with detections
  ros::WallTimer watchdog_;
  mutable std::mutex mutex_;
  std::unique_ptr<InputMonitor> monitor_;
  TimeJumpGate jump_gate_;  ///< under mutex_
  double newest_stamp_s_ = 0.0;
};

}  // namespace geofusion
