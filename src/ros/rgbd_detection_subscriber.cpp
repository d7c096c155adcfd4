#include "geofusion/ros/rgbd_detection_subscriber.h"

#include "geofusion/ros/params.h"

#include <boost/bind/bind.hpp>

namespace geofusion {

RgbdDetectionSubscriber::Config RgbdDetectionSubscriber::configFromParams(
    const ros::NodeHandle& pnh, double warn_period_s) {
  Config sub;
  pnh.param("rgb_topic", sub.rgb_topic, sub.rgb_topic);
  pnh.param("depth_topic", sub.depth_topic, sub.depth_topic);
  pnh.param("camera_info_topic", sub.camera_info_topic, sub.camera_info_topic);
  pnh.param("detections_topic", sub.detections_topic, sub.detections_topic);
  sub.queue_size = paramAtLeast(pnh, "queue_size", 10, 1);
  sub.max_interval_s = paramAtLeast(pnh, "sync_max_interval_s", 0.05, 0.0);
  sub.warn_period_s = warn_period_s;
  sub.monitor.stale_after_s = paramAtLeast(pnh, "stale_after_s", 3.0, 0.1);
  sub.monitor.sync_timeout_s = paramAtLeast(pnh, "sync_timeout_s", 3.0, 0.1);
  return sub;
}

namespace {
double wallNow() {
  return ros::WallTime::now().toSec();
}
}  // namespace

RgbdDetectionSubscriber::RgbdDetectionSubscriber(ros::NodeHandle nh, const Config& config,
                                                 FrameCallback on_frame,
                                                 TimeJumpCallback on_time_jump)
    : nh_(nh),
      config_(config),
      on_frame_(std::move(on_frame)),
      on_time_jump_(std::move(on_time_jump)),
      it_(nh) {
  const image_transport::TransportHints hints("raw", ros::TransportHints(), nh_);
  rgb_sub_ = it_.subscribe(config_.rgb_topic, config_.queue_size,
                           &RgbdDetectionSubscriber::onInput<0, sensor_msgs::Image>, this, hints);
  depth_sub_ = it_.subscribe(config_.depth_topic, config_.queue_size,
                             &RgbdDetectionSubscriber::onInput<1, sensor_msgs::Image>, this, hints);
  info_sub_ = nh_.subscribe(config_.camera_info_topic, config_.queue_size,
                            &RgbdDetectionSubscriber::onInput<2, sensor_msgs::CameraInfo>, this);
  detections_sub_ =
      nh_.subscribe(config_.detections_topic, config_.queue_size,
                    &RgbdDetectionSubscriber::onInput<3, geofusion::DetectionArray>, this);

  monitor_ = std::make_unique<InputMonitor>(topics(), config_.monitor, wallNow());
  {
    std::lock_guard<std::mutex> lock(sync_mutex_);
    makeSynchronizer();
  }
  watchdog_ = nh_.createWallTimer(ros::WallDuration(config_.warn_period_s),
                                  &RgbdDetectionSubscriber::onWatchdog, this);
  ROS_INFO("geofusion: waiting for synchronised %s, %s, %s and %s", topics()[0].c_str(),
           topics()[1].c_str(), topics()[2].c_str(), topics()[3].c_str());
}

RgbdDetectionSubscriber::~RgbdDetectionSubscriber() {
  watchdog_.stop();
}

template <int I, class M>
void RgbdDetectionSubscriber::onInput(const boost::shared_ptr<M const>& msg) {
  noteInput(I, msg->header.stamp);
  std::lock_guard<std::mutex> lock(sync_mutex_);
  sync_->template add<I>(msg);
}

void RgbdDetectionSubscriber::makeSynchronizer() {
  sync_ = std::make_unique<Sync>(Policy(config_.queue_size));
  sync_->setMaxIntervalDuration(ros::Duration(config_.max_interval_s));
  sync_->registerCallback(boost::bind(&RgbdDetectionSubscriber::onSynchronized, this,
                                      boost::placeholders::_1, boost::placeholders::_2,
                                      boost::placeholders::_3, boost::placeholders::_4));
}

std::vector<std::string> RgbdDetectionSubscriber::topics() const {
  return {nh_.resolveName(config_.rgb_topic), nh_.resolveName(config_.depth_topic),
          nh_.resolveName(config_.camera_info_topic), nh_.resolveName(config_.detections_topic)};
}

std::vector<std::size_t> RgbdDetectionSubscriber::messageCounts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < monitor_->inputNames().size(); ++i)
    out.push_back(monitor_->messageCount(i));
  return out;
}

std::size_t RgbdDetectionSubscriber::synchronizedCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return monitor_->synchronizedCount();
}

void RgbdDetectionSubscriber::noteInput(std::size_t index, const ros::Time& stamp) {
  bool jumped = false;
  ros::Time from;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (index == 0) {
      if (!last_rgb_stamp_.isZero() &&
          stamp + ros::Duration(config_.time_jump_tolerance_s) < last_rgb_stamp_) {
        jumped = true;
        from = last_rgb_stamp_;
        monitor_->reset(wallNow());
      }
      last_rgb_stamp_ = stamp;
    }
    monitor_->onMessage(index, wallNow());
  }
  if (jumped) {
    ROS_WARN(
        "geofusion: time jumped back from %.3f to %.3f on %s (a looping bag or a restarted "
        "driver?); restarting synchronisation",
        from.toSec(), stamp.toSec(), topics()[0].c_str());
    // The old synchroniser holds messages from the future: start a fresh one.
    {
      std::lock_guard<std::mutex> lock(sync_mutex_);
      makeSynchronizer();
    }
    if (on_time_jump_) on_time_jump_(from, stamp);
  }
}

void RgbdDetectionSubscriber::onSynchronized(const sensor_msgs::ImageConstPtr& rgb,
                                             const sensor_msgs::ImageConstPtr& depth,
                                             const sensor_msgs::CameraInfoConstPtr& info,
                                             const geofusion::DetectionArrayConstPtr& dets) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    monitor_->onSynchronized(wallNow());
  }
  on_frame_(rgb, depth, info, dets);
}

void RgbdDetectionSubscriber::onWatchdog(const ros::WallTimerEvent&) {
  std::vector<std::string> problems;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    problems = monitor_->problems(wallNow());
  }
  for (const std::string& p : problems) ROS_WARN("geofusion: %s", p.c_str());
}

}  // namespace geofusion
