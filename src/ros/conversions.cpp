#include "geofusion/ros/conversions.h"

namespace geofusion {

RawDetection fromMsg(const geofusion::Detection& msg) {
  RawDetection d;
  d.class_name = msg.class_name;
  d.class_id = msg.class_id;
  d.score = msg.score;
  d.position_cam = Eigen::Vector3d(msg.pose.position.x, msg.pose.position.y, msg.pose.position.z);
  d.orientation_cam = Eigen::Quaterniond(msg.pose.orientation.w, msg.pose.orientation.x,
                                         msg.pose.orientation.y, msg.pose.orientation.z);
  d.box = PixelBox{static_cast<int>(msg.box.x_offset), static_cast<int>(msg.box.y_offset),
                   static_cast<int>(msg.box.width), static_cast<int>(msg.box.height)};
  return d;
}

std::vector<RawDetection> fromMsg(const geofusion::DetectionArray& msg) {
  std::vector<RawDetection> out;
  out.reserve(msg.detections.size());
  for (const auto& d : msg.detections) out.push_back(fromMsg(d));
  return out;
}

geofusion::Detection toMsg(const RawDetection& d) {
  geofusion::Detection msg;
  msg.class_name = d.class_name;
  msg.class_id = d.class_id;
  msg.score = static_cast<float>(d.score);
  msg.pose.position.x = d.position_cam.x();
  msg.pose.position.y = d.position_cam.y();
  msg.pose.position.z = d.position_cam.z();
  msg.pose.orientation.w = d.orientation_cam.w();
  msg.pose.orientation.x = d.orientation_cam.x();
  msg.pose.orientation.y = d.orientation_cam.y();
  msg.pose.orientation.z = d.orientation_cam.z();
  if (d.box.valid()) {
    msg.box.x_offset = static_cast<uint32_t>(std::max(0, d.box.x));
    msg.box.y_offset = static_cast<uint32_t>(std::max(0, d.box.y));
    msg.box.width = static_cast<uint32_t>(d.box.width);
    msg.box.height = static_cast<uint32_t>(d.box.height);
  }
  return msg;
}

geometry_msgs::Pose toPoseMsg(const Eigen::Isometry3d& T) {
  geometry_msgs::Pose p;
  p.position.x = T.translation().x();
  p.position.y = T.translation().y();
  p.position.z = T.translation().z();
  const Eigen::Quaterniond q(T.linear());
  p.orientation.w = q.w();
  p.orientation.x = q.x();
  p.orientation.y = q.y();
  p.orientation.z = q.z();
  return p;
}

}  // namespace geofusion
