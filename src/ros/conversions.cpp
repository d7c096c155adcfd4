#include "geofusion/ros/conversions.h"

#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/distortion_models.h>
#include <sensor_msgs/image_encodings.h>

#include <cmath>
#include <cstring>

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

const char* depthProblem(const sensor_msgs::Image& depth) {
  namespace enc = sensor_msgs::image_encodings;
  if (depth.width == 0 || depth.height == 0 || depth.data.empty()) return "empty depth image";
  if (depth.encoding != enc::TYPE_32FC1 && depth.encoding != enc::TYPE_16UC1) {
    return "depth encoding is neither 32FC1 (metres) nor 16UC1 (millimetres)";
  }
  const std::size_t pixel = depth.encoding == enc::TYPE_32FC1 ? 4 : 2;
  if (depth.step < depth.width * pixel ||
      depth.data.size() < static_cast<std::size_t>(depth.step) * depth.height) {
    return "depth data shorter than step * height";
  }
  return nullptr;
}

bool depthToMetres(const sensor_msgs::Image& depth, std::vector<float>* metres) {
  if (depthProblem(depth)) return false;
  const bool is_float = depth.encoding == sensor_msgs::image_encodings::TYPE_32FC1;
  metres->assign(static_cast<std::size_t>(depth.width) * depth.height, 0.f);
  for (uint32_t v = 0; v < depth.height; ++v) {
    const uint8_t* row = depth.data.data() + static_cast<std::size_t>(v) * depth.step;
    for (uint32_t u = 0; u < depth.width; ++u) {
      float z;
      if (is_float) {
        std::memcpy(&z, row + 4 * u, sizeof(float));
      } else {
        uint16_t mm;
        std::memcpy(&mm, row + 2 * u, sizeof(uint16_t));
        z = static_cast<float>(mm) * 0.001f;
      }
      (*metres)[static_cast<std::size_t>(v) * depth.width + u] =
          std::isfinite(z) && z > 0.f ? z : 0.f;
    }
  }
  return true;
}

geometry_msgs::Point toPointMsg(const Eigen::Vector3d& p) {
  geometry_msgs::Point out;
  out.x = p.x(), out.y = p.y(), out.z = p.z();
  return out;
}

geometry_msgs::Twist twistBetween(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to,
                                  double dt) {
  geometry_msgs::Twist t;
  if (dt <= 0.0) return t;
  const Eigen::Isometry3d delta = from.inverse() * to;
  const Eigen::AngleAxisd rotation(delta.linear());
  const Eigen::Vector3d v = delta.translation() / dt, w = rotation.angle() * rotation.axis() / dt;
  t.linear.x = v.x(), t.linear.y = v.y(), t.linear.z = v.z();
  t.angular.x = w.x(), t.angular.y = w.y(), t.angular.z = w.z();
  return t;
}

bool toGray(const sensor_msgs::Image& image, std::vector<std::uint8_t>* gray, std::string* error) {
  if (image.width == 0 || image.height == 0 ||
      image.data.size() < static_cast<std::size_t>(image.step) * image.height) {
    if (error) *error = "empty or truncated image";
    return false;
  }
  cv_bridge::CvImageConstPtr cv;
  try {
    cv = cv_bridge::toCvCopy(image, sensor_msgs::image_encodings::MONO8);
  } catch (const std::exception& e) {
    if (error)
      *error = std::string("cannot convert '") + image.encoding + "' to mono8: " + e.what();
    return false;
  }
  gray->resize(static_cast<std::size_t>(cv->image.cols) * cv->image.rows);
  for (int r = 0; r < cv->image.rows; ++r)
    std::memcpy(gray->data() + static_cast<std::size_t>(r) * cv->image.cols,
                cv->image.ptr<std::uint8_t>(r), static_cast<std::size_t>(cv->image.cols));
  return true;
}

PinholeIntrinsics intrinsicsFromCameraInfo(const sensor_msgs::CameraInfo& info) {
  PinholeIntrinsics K;
  K.width = static_cast<int>(info.width);
  K.height = static_cast<int>(info.height);
  K.fx = info.K[0];
  K.fy = info.K[4];
  K.cx = info.K[2];
  K.cy = info.K[5];
  return K;
}

bool lensFromCameraInfo(const sensor_msgs::CameraInfo& info, LensDistortion* lens,
                        std::string* error) {
  LensDistortion l{std::vector<double>(info.D.begin(), info.D.end())};
  if (!l.any()) {
    *lens = LensDistortion{};
    return true;
  }
  const std::string& model = info.distortion_model;
  const std::size_t expected = model == sensor_msgs::distortion_models::PLUMB_BOB             ? 5
                               : model == sensor_msgs::distortion_models::RATIONAL_POLYNOMIAL ? 8
                                                                                              : 0;
  if (expected == 0) {
    *error = "camera_info distortion model '" + model +
             "' is not supported (plumb_bob or rational_polynomial; or rectified images with D "
             "all zero)";
    return false;
  }
  if (l.D.size() != expected) {
    *error = "camera_info distortion model " + model + " with " + std::to_string(l.D.size()) +
             " coefficients (it takes " + std::to_string(expected) + ")";
    return false;
  }
  if (const std::string problem = l.problem(); !problem.empty()) {
    *error = "camera_info: " + problem;
    return false;
  }
  *lens = std::move(l);
  return true;
}

bool CameraRectifier::update(const sensor_msgs::CameraInfo& info, std::string* error) {
  const PinholeIntrinsics K = intrinsicsFromCameraInfo(info);
  if (!K.valid() || !std::isfinite(K.fx) || !std::isfinite(K.fy) || !std::isfinite(K.cx) ||
      !std::isfinite(K.cy)) {
    *error = "camera_info K is not a camera (size " + std::to_string(info.width) + "x" +
             std::to_string(info.height) + ", fx " + std::to_string(info.K[0]) + ", fy " +
             std::to_string(info.K[4]) + ")";
    return false;
  }
  LensDistortion lens;
  if (!lensFromCameraInfo(info, &lens, error)) return false;
  if (lens.any() && (K.width >= kMaxWarpSide || K.height >= kMaxWarpSide)) {
    *error = "camera_info: a " + std::to_string(K.width) + "x" + std::to_string(K.height) +
             " image with lens distortion is too large to rectify";
    return false;
  }
  K_ = K;
  lens_ = std::move(lens);
  return true;
}

bool odometryImages(const sensor_msgs::Image& rgb, const sensor_msgs::Image& depth,
                    const sensor_msgs::CameraInfo& info, CameraRectifier* camera,
                    std::vector<std::uint8_t>* gray, std::vector<float>* metres,
                    std::string* error) {
  if (!toGray(rgb, gray, error)) return false;
  if (!depthToMetres(depth, metres)) {
    const char* why = depthProblem(depth);
    *error = why ? why : "depth not convertible";
    return false;
  }
  if (rgb.width != depth.width || rgb.height != depth.height) {
    *error = "RGB and depth sizes differ";
    return false;
  }
  if (!camera->update(info, error)) return false;
  if (!camera->rectifyGrey(gray) || !camera->rectifyDepth(metres)) {
    *error = "the images are not the size camera_info says";
    return false;
  }
  return true;
}

}  // namespace geofusion
