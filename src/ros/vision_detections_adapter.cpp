#include "geofusion/ros/vision_detections_adapter.h"

#include "geofusion/common/robot_names.h"
#include "geofusion/model/object_model.h"
#include "geofusion/ros/node_config.h"

#include <ros/serialization.h>

#include <stdexcept>
#include <vector>

namespace geofusion {

VisionDetectionsAdapter::VisionDetectionsAdapter(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh), pnh_(pnh) {
  const GeoFusionConfig config = loadNodeConfig(pnh_, {"vision_detections_topic"});
  std::string in_topic = "vision_detections", out_topic = kDetectionsTopic;
  pnh_.param("vision_detections_topic", in_topic, in_topic);
  pnh_.param("detections_topic", out_topic, out_topic);
  warn_period_s_ = config.input.warn_period_s;
  const ModelSet models = loadNodeModelSet(config);
  std::map<std::int64_t, ModelClass> class_map;
  std::string error;
  if (!makeVisionClassMap(config.vision_msgs.class_map, models, &class_map, &error))
    throw std::runtime_error(error + "; not starting");
  converter_ = std::make_unique<VisionDetectionConverter>(std::move(class_map));
  publishEffectiveConfig(pnh_, config);
  pub_ = nh_.advertise<geofusion::DetectionArray>(out_topic, 10);
  sub_ = nh_.subscribe(in_topic, 10, &VisionDetectionsAdapter::onMessage, this);
  ROS_INFO("geofusion: vision_msgs adapter: %s (%s) -> %s, %zu class ids mapped",
           sub_.getTopic().c_str(), kVisionDetectionsType, pub_.getTopic().c_str(),
           converter_->classCount());
}

VisionDetectionsAdapter::~VisionDetectionsAdapter() {
  sub_.shutdown();
  std::lock_guard<std::mutex> lock(mutex_);
  const auto& c = converter_->counts();
  ROS_INFO("geofusion: vision_msgs adapter summary: %zu messages, %zu detections converted%s%s",
           c.messages, c.detections, converter_->droppedSummary().empty() ? "" : "; dropped: ",
           converter_->droppedSummary().c_str());
}

void VisionDetectionsAdapter::onMessage(const topic_tools::ShapeShifter::ConstPtr& msg) {
  std::vector<std::uint8_t> bytes(msg->size());
  ros::serialization::OStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  msg->write(stream);
  geofusion::DetectionArray out;
  std::string error;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!converter_->convert(msg->getDataType(), msg->getMD5Sum(), bytes.data(), bytes.size(), &out,
                           &error)) {
    ROS_ERROR_STREAM_THROTTLE(warn_period_s_, "geofusion: vision_msgs adapter: message on "
                                                  << sub_.getTopic() << " dropped: " << error);
    return;
  }
  const std::string dropped = converter_->droppedSummary();
  if (dropped != reported_) {
    ROS_WARN_STREAM_THROTTLE(warn_period_s_,
                             "geofusion: vision_msgs adapter dropped so far: " << dropped);
    reported_ = dropped;
  }
  pub_.publish(out);
}

}  // namespace geofusion
