#include "geofusion/ros/rgbd_subscriber.h"

#include <algorithm>
#include <boost/bind/bind.hpp>

namespace geofusion {

RgbdSubscriber::Config RgbdSubscriber::configOf(const ros::NodeHandle& pnh,
                                                const InputConfig& input, bool with_detections) {
  Config sub;
  pnh.param("rgb_topic", sub.rgb_topic, sub.rgb_topic);
  pnh.param("depth_topic", sub.depth_topic, sub.depth_topic);
  pnh.param("camera_info_topic", sub.camera_info_topic, sub.camera_info_topic);
  if (with_detections) {
    pnh.param("detections_topic", sub.detections_topic, sub.detections_topic);
  } else {
    sub.detections_topic.clear();
  }
  sub.queue_size = input.queue_size;
  sub.max_interval_s = input.sync_max_interval_s;
  sub.time_jump_tolerance_s = input.time_jump_tolerance_s;
  sub.warn_period_s = input.warn_period_s;
  sub.monitor.stale_after_s = input.stale_after_s;
  sub.monitor.sync_timeout_s = input.sync_timeout_s;
  return sub;
}

namespace {
double wallNow() {
  return ros::WallTime::now().toSec();
}
}  // namespace

RgbdSubscriber::RgbdSubscriber(ros::NodeHandle nh, const Config& config, FrameCallback on_frame,
                               TimeJumpCallback on_time_jump)
    : nh_(nh),
      config_(config),
      on_frame_(std::move(on_frame)),
      on_time_jump_(std::move(on_time_jump)),
      it_(nh),
      jump_gate_(withDetections() ? 4 : 3, config_.time_jump_tolerance_s) {
  const image_transport::TransportHints hints("raw", ros::TransportHints(), nh_);
  rgb_sub_ = it_.subscribe(config_.rgb_topic, config_.queue_size,
                           &RgbdSubscriber::onInput<0, sensor_msgs::Image>, this, hints);
  depth_sub_ = it_.subscribe(config_.depth_topic, config_.queue_size,
                             &RgbdSubscriber::onInput<1, sensor_msgs::Image>, this, hints);
  info_sub_ = nh_.subscribe(config_.camera_info_topic, config_.queue_size,
                            &RgbdSubscriber::onInput<2, sensor_msgs::CameraInfo>, this);
  if (withDetections()) {
    detections_sub_ = nh_.subscribe(config_.detections_topic, config_.queue_size,
                                    &RgbdSubscriber::onInput<3, geofusion::DetectionArray>, this);
  }

  monitor_ = std::make_unique<InputMonitor>(topics(), config_.monitor, wallNow());
  {
    std::lock_guard<std::mutex> lock(sync_mutex_);
    makeSynchronizer();
  }
  watchdog_ = nh_.createWallTimer(ros::WallDuration(config_.warn_period_s),
                                  &RgbdSubscriber::onWatchdog, this);
  std::string names;
  for (const std::string& t : topics()) names += (names.empty() ? "" : ", ") + t;
  ROS_INFO("geofusion: waiting for synchronised %s", names.c_str());
}

RgbdSubscriber::~RgbdSubscriber() {
  watchdog_.stop();
}

template <int I, class M>
void RgbdSubscriber::onInput(const boost::shared_ptr<M const>& msg) {
  if (!noteInput(I, msg->header.stamp)) return;
  std::lock_guard<std::mutex> lock(sync_mutex_);
  if (detection_sync_) {
    detection_sync_->template add<I>(msg);
  } else if constexpr (I < 3) {
    rgbd_sync_->template add<I>(msg);
  }
}

void RgbdSubscriber::makeSynchronizer() {
  using boost::placeholders::_1;
  using boost::placeholders::_2;
  using boost::placeholders::_3;
  using boost::placeholders::_4;
  if (withDetections()) {
    detection_sync_ = makeDetectionSync(config_);
    detection_sync_->registerCallback(
        boost::bind(&RgbdSubscriber::onSynchronized, this, _1, _2, _3, _4));
  } else {
    rgbd_sync_ = std::make_unique<RgbdSync>(RgbdPolicy(config_.queue_size));
    rgbd_sync_->setMaxIntervalDuration(ros::Duration(config_.max_interval_s));
    rgbd_sync_->registerCallback(boost::bind(&RgbdSubscriber::onSynchronized, this, _1, _2, _3,
                                             geofusion::DetectionArrayConstPtr()));
  }
}

std::unique_ptr<RgbdSubscriber::DetectionSync> RgbdSubscriber::makeDetectionSync(
    const Config& config) {
  auto sync = std::make_unique<DetectionSync>(DetectionPolicy(config.queue_size));
  sync->setMaxIntervalDuration(ros::Duration(config.max_interval_s));
  return sync;
}

double RgbdSubscriber::newestStamp() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return newest_stamp_s_;
}

std::vector<std::string> RgbdSubscriber::topics() const {
  std::vector<std::string> out{nh_.resolveName(config_.rgb_topic),
                               nh_.resolveName(config_.depth_topic),
                               nh_.resolveName(config_.camera_info_topic)};
  if (withDetections()) out.push_back(nh_.resolveName(config_.detections_topic));
  return out;
}

std::vector<std::size_t> RgbdSubscriber::messageCounts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < monitor_->inputNames().size(); ++i)
    out.push_back(monitor_->messageCount(i));
  return out;
}

std::size_t RgbdSubscriber::synchronizedCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return monitor_->synchronizedCount();
}

bool RgbdSubscriber::noteInput(std::size_t index, const ros::Time& stamp) {
  TimeJumpGate::Decision d;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    d = jump_gate_.onMessage(index, stamp.toSec(), wallNow());
    if (d.jumped) {
      monitor_->reset(wallNow());
      newest_stamp_s_ = 0.0;
    }
    if (d.keep) newest_stamp_s_ = std::max(newest_stamp_s_, stamp.toSec());
    monitor_->onMessage(index, wallNow());
  }
  if (!d.keep) {
    ROS_DEBUG("geofusion: a message on %s from before the time jump dropped",
              topics()[index].c_str());
  }
  if (d.jumped) {
    ROS_WARN(
        "geofusion: time jumped back from %.3f to %.3f on %s (a looping bag or a restarted "
        "driver?); restarting synchronisation",
        d.from_s, stamp.toSec(), topics()[index].c_str());
    // The old synchroniser holds messages from the future: start a fresh one.
    {
      std::lock_guard<std::mutex> lock(sync_mutex_);
      makeSynchronizer();
    }
    if (on_time_jump_) on_time_jump_(ros::Time(d.from_s), stamp);
  }
  return d.keep;
}

void RgbdSubscriber::onSynchronized(const sensor_msgs::ImageConstPtr& rgb,
                                    const sensor_msgs::ImageConstPtr& depth,
                                    const sensor_msgs::CameraInfoConstPtr& info,
                                    const geofusion::DetectionArrayConstPtr& dets) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    monitor_->onSynchronized(wallNow());
  }
  on_frame_(rgb, depth, info, dets);
}

void RgbdSubscriber::onWatchdog(const ros::WallTimerEvent&) {
  std::vector<std::string> problems;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    problems = monitor_->problems(wallNow());
  }
  for (const std::string& p : problems) ROS_WARN("geofusion: %s", p.c_str());
}

}  // namespace geofusion
