#include "geofusion/common/lens.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <sstream>

namespace geofusion {

bool LensDistortion::any() const {
  for (double d : D)
    if (d != 0.0) return true;
  return false;
}

std::string LensDistortion::problem() const {
  if (!(D.empty() || D.size() == 4 || D.size() == 5 || D.size() == 8)) {
    return "distortion has " + std::to_string(D.size()) +
           " coefficients (plumb_bob takes 5, rational_polynomial 8)";
  }
  for (double d : D)
    if (!std::isfinite(d)) return "a distortion coefficient is not finite";
  return "";
}

std::string LensDistortion::describe() const {
  if (!any()) return "none";
  std::ostringstream o;
  o.precision(6);
  for (std::size_t i = 0; i < D.size(); ++i) o << (i ? " " : "") << D[i];
  return o.str();
}

LensDistortion LensDistortion::primesense() {
  return LensDistortion{{0.2312, -0.7849, -0.0033, -0.0001, 0.9172}};
}

// One direction's maps for the K and D they were made for.
struct LensWarp::Maps {
  PinholeIntrinsics K;
  std::vector<double> D;
  cv::Mat map_x, map_y;  // CV_32FC1: where in the source image each output pixel comes from
};

namespace {

cv::Mat cameraMatrix(const PinholeIntrinsics& K) {
  return (cv::Mat_<double>(3, 3) << K.fx, 0.0, K.cx, 0.0, K.fy, K.cy, 0.0, 0.0, 1.0);
}

bool sameCamera(const PinholeIntrinsics& a, const PinholeIntrinsics& b) {
  return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy &&
         a.cx == b.cx && a.cy == b.cy;
}

// Rectifying: each pinhole pixel looks up its raw position (OpenCV's own rectification map).
void rectifyMaps(const PinholeIntrinsics& K, const std::vector<double>& D, cv::Mat* mx,
                 cv::Mat* my) {
  const cv::Mat Km = cameraMatrix(K);
  cv::initUndistortRectifyMap(Km, cv::Mat(D), cv::Mat(), Km, cv::Size(K.width, K.height), CV_32FC1,
                              *mx, *my);
}

// Distorting: each raw pixel looks up its pinhole position, the lens model inverted by
// undistortPoints' iteration (run to convergence, the default 5 steps leave a pixel at the
// corners).
void distortMaps(const PinholeIntrinsics& K, const std::vector<double>& D, cv::Mat* mx,
                 cv::Mat* my) {
  std::vector<cv::Point2f> raw;
  raw.reserve(static_cast<std::size_t>(K.width) * K.height);
  for (int v = 0; v < K.height; ++v)
    for (int u = 0; u < K.width; ++u)
      raw.emplace_back(static_cast<float>(u), static_cast<float>(v));
  std::vector<cv::Point2f> pinhole;
  const cv::Mat Km = cameraMatrix(K);
  cv::undistortPoints(raw, pinhole, Km, cv::Mat(D), cv::noArray(), Km,
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 1e-6));
  mx->create(K.height, K.width, CV_32FC1);
  my->create(K.height, K.width, CV_32FC1);
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const cv::Point2f& p = pinhole[static_cast<std::size_t>(v) * K.width + u];
      mx->at<float>(v, u) = p.x;
      my->at<float>(v, u) = p.y;
    }
  }
}

}  // namespace

LensWarp::LensWarp() = default;
LensWarp::~LensWarp() = default;

bool LensWarp::warp(const PinholeIntrinsics& K, const LensDistortion& D, bool rectify, int type,
                    bool nearest, void* data, std::size_t size) {
  if (!K.valid() || !D.problem().empty()) return false;
  const cv::Mat probe(1, 1, type);
  if (size != static_cast<std::size_t>(K.width) * K.height * probe.elemSize()) return false;
  if (!D.any()) return true;
  if (K.width >= kMaxWarpSide || K.height >= kMaxWarpSide) return false;  // remap's limit
  std::unique_ptr<Maps>& maps = rectify ? rectify_ : distort_;
  if (!maps || !sameCamera(maps->K, K) || maps->D != D.D) {
    maps = std::make_unique<Maps>();
    maps->K = K;
    maps->D = D.D;
    try {
      if (rectify)
        rectifyMaps(K, D.D, &maps->map_x, &maps->map_y);
      else
        distortMaps(K, D.D, &maps->map_x, &maps->map_y);
    } catch (const cv::Exception&) {
      maps.reset();
      return false;
    }
  }
  try {
    cv::Mat image(K.height, K.width, type, data);
    cv::Mat out;
    cv::remap(image, out, maps->map_x, maps->map_y, nearest ? cv::INTER_NEAREST : cv::INTER_LINEAR,
              cv::BORDER_CONSTANT, cv::Scalar::all(0));
    out.copyTo(image);
  } catch (const cv::Exception&) {  // a camera OpenCV cannot warp: refused, never a crash
    maps.reset();
    return false;
  }
  return true;
}

bool LensWarp::rectifyDepth(const PinholeIntrinsics& K, const LensDistortion& D,
                            std::vector<float>* depth) {
  return warp(K, D, true, CV_32FC1, true, depth->data(), depth->size() * sizeof(float));
}

bool LensWarp::rectifyGrey(const PinholeIntrinsics& K, const LensDistortion& D,
                           std::vector<std::uint8_t>* grey) {
  return warp(K, D, true, CV_8UC1, false, grey->data(), grey->size());
}

bool LensWarp::rectifyRgb(const PinholeIntrinsics& K, const LensDistortion& D,
                          std::vector<std::uint8_t>* rgb) {
  return warp(K, D, true, CV_8UC3, false, rgb->data(), rgb->size());
}

bool LensWarp::distortDepth(const PinholeIntrinsics& K, const LensDistortion& D,
                            std::vector<float>* depth) {
  return warp(K, D, false, CV_32FC1, true, depth->data(), depth->size() * sizeof(float));
}

bool LensWarp::distortRgb(const PinholeIntrinsics& K, const LensDistortion& D,
                          std::vector<std::uint8_t>* rgb) {
  return warp(K, D, false, CV_8UC3, false, rgb->data(), rgb->size());
}

}  // namespace geofusion
