// The colour camera's motion blur, rolling shutter, auto exposure and noise (colour_camera.h).
#include "geofusion/simulation/colour_camera.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace geofusion {

ColourNoise ColourNoise::fetchHead() {
  ColourNoise n;
  n.enabled = true;
  return n;
}

std::string ColourNoise::describe() const {
  std::ostringstream o;
  o.precision(9);
  o << exposure_s << " " << readout_s << " " << read_noise_dn << " " << shot_noise << " "
    << exposure_walk << " " << exposure_range;
  return o.str();
}

ColourCamera::ColourCamera(const ColourNoise& noise, unsigned seed) : noise_(noise), rng_(seed) {}

void ColourCamera::apply(const PinholeIntrinsics& K, const Eigen::Isometry3d& T_map_prev,
                         const Eigen::Isometry3d& T_map_cur, double dt_s, double scene_depth_m,
                         std::vector<std::uint8_t>* rgb) {
  const int W = K.width, H = K.height;
  if (rgb->size() != static_cast<std::size_t>(3) * W * H || !(dt_s > 0.0)) return;
  // Image motion: where a point at the scene's depth on the previous optical axis lands now.
  const double z = scene_depth_m > 0.1 ? scene_depth_m : 1.0;
  const Eigen::Vector3d p_cur = T_map_cur.inverse() * (T_map_prev * Eigen::Vector3d(0, 0, z));
  flow_ = p_cur.z() > 1e-3
              ? Eigen::Vector2d((K.project(p_cur) - Eigen::Vector2d(K.cx, K.cy)) / dt_s)
              : Eigen::Vector2d::Zero();
  cv::Mat image(H, W, CV_8UC3, rgb->data());
  // Rolling shutter: row v is read (v / H - 1/2) * readout after the middle row; the scene has
  // moved on by the flow over that time.
  if (noise_.readout_s > 0.0 && flow_.norm() > 1e-6) {
    cv::Mat map_x(H, W, CV_32F), map_y(H, W, CV_32F);
    for (int v = 0; v < H; ++v) {
      const double tau = (static_cast<double>(v) / H - 0.5) * noise_.readout_s;
      for (int u = 0; u < W; ++u) {
        map_x.at<float>(v, u) = static_cast<float>(u - flow_.x() * tau);
        map_y.at<float>(v, u) = static_cast<float>(v - flow_.y() * tau);
      }
    }
    cv::Mat sheared;
    cv::remap(image, sheared, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    sheared.copyTo(image);
  }
  // Motion blur: a line kernel as long as the image moves while the shutter is open.
  const Eigen::Vector2d smear = flow_ * noise_.exposure_s;
  const double length = smear.norm();
  if (length >= 1.0) {
    const int size = 2 * static_cast<int>(std::ceil(length / 2.0)) + 1;
    cv::Mat kernel = cv::Mat::zeros(size, size, CV_32F);
    const cv::Point2d c(size / 2, size / 2), half(smear.x() / 2.0, smear.y() / 2.0);
    cv::line(kernel, c - half, c + half, cv::Scalar(1.0), 1, cv::LINE_AA);
    kernel /= cv::sum(kernel)[0];
    cv::Mat blurred;
    cv::filter2D(image, blurred, -1, kernel, cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);
    blurred.copyTo(image);
  }
  // Auto exposure drifts; read and shot noise.
  std::normal_distribution<double> gauss(0.0, 1.0);
  gain_ = std::clamp(gain_ * std::exp(noise_.exposure_walk * gauss(rng_)),
                     1.0 - noise_.exposure_range, 1.0 + noise_.exposure_range);
  for (std::uint8_t& value : *rgb) {
    const double level = gain_ * value;
    const double sigma = noise_.read_noise_dn + noise_.shot_noise * std::sqrt(level);
    value =
        static_cast<std::uint8_t>(std::clamp(std::lround(level + sigma * gauss(rng_)), 0L, 255L));
  }
}

}  // namespace geofusion
