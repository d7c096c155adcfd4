#include "geofusion/core/visual_odometry.h"

#include <ceres/ceres.h>
#include <mrpt/math/CQuaternion.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/hal/hal.hpp>
#include <opencv2/features2d.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <vector>

namespace geofusion {

const char* toString(TrackingState state) {
  switch (state) {
    case TrackingState::kNotStarted: return "not started";
    case TrackingState::kTracking: return "tracking";
    case TrackingState::kLost: return "lost";
  }
  return "?";
}

namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

mrpt::poses::CPose3D toMrpt(const Eigen::Isometry3d& T) {
  const Eigen::Quaterniond q(T.linear());
  const Eigen::Vector3d& t = T.translation();
  return mrpt::poses::CPose3D(mrpt::math::CQuaternionDouble(q.w(), q.x(), q.y(), q.z()), t.x(),
                              t.y(), t.z());
}

/// MRPT's 6D parameters of a pose: x, y, z, yaw, pitch, roll.
Vector6d mrptVector(const Eigen::Isometry3d& T) {
  const mrpt::poses::CPose3D p = toMrpt(T);
  Vector6d v;
  v << p.x(), p.y(), p.z(), p.yaw(), p.pitch(), p.roll();
  return v;
}

/// exp of a small right perturbation (translation, rotation vector).
Eigen::Isometry3d perturbation(const Vector6d& xi) {
  Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
  const double angle = xi.tail<3>().norm();
  if (angle > 0.0) D.linear() = Eigen::AngleAxisd(angle, xi.tail<3>() / angle).toRotationMatrix();
  D.translation() = xi.head<3>();
  return D;
}

/// Covariance of right perturbations of T, expressed in MRPT's parameters of T (numeric
/// Jacobian; angles differenced with wrapping).
Matrix6d toMrptCovariance(const Eigen::Isometry3d& T, const Matrix6d& cov_right) {
  Matrix6d J;
  const double h = 1e-6;
  for (int i = 0; i < 6; ++i) {
    Vector6d d = Vector6d::Zero();
    d[i] = h;
    Vector6d diff = mrptVector(T * perturbation(d)) - mrptVector(T * perturbation(-d));
    for (int k = 3; k < 6; ++k) diff[k] = std::remainder(diff[k], 2.0 * M_PI);
    J.col(i) = diff / (2.0 * h);
  }
  return J * cov_right * J.transpose();
}

Matrix6d fromMrpt(const mrpt::math::CMatrixDouble66& m) {
  Matrix6d out;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) out(r, c) = m(r, c);
  return out;
}

mrpt::math::CMatrixDouble66 toMrptMatrix(const Matrix6d& m) {
  mrpt::math::CMatrixDouble66 out;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) out(r, c) = m(r, c);
  return out;
}

/// MRPT (x, y, z, yaw, pitch, roll) -> ROS (x, y, z, roll, pitch, yaw) covariance.
Matrix6d rosOrder(const Matrix6d& mrpt_cov) {
  const int perm[6] = {0, 1, 2, 5, 4, 3};
  Matrix6d out;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) out(r, c) = mrpt_cov(perm[r], perm[c]);
  return out;
}

struct ReprojectionCost {
  ReprojectionCost(const Eigen::Vector3d& P, const Eigen::Vector2d& uv, const PinholeIntrinsics& K)
      : P_(P), uv_(uv), fx_(K.fx), fy_(K.fy), cx_(K.cx), cy_(K.cy) {}
  template <typename T>
  bool operator()(const T* q_cam_odom, const T* t_cam_odom, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_cam_odom);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(t_cam_odom);
    const Eigen::Matrix<T, 3, 1> p = q * P_.cast<T>() + t;
    if (p.z() < T(1e-3)) return false;
    r[0] = T(fx_) * p.x() / p.z() + T(cx_) - T(uv_.x());
    r[1] = T(fy_) * p.y() / p.z() + T(cy_) - T(uv_.y());
    return true;
  }
  Eigen::Vector3d P_;
  Eigen::Vector2d uv_;
  double fx_, fy_, cx_, cy_;
};

struct VoKeyframe {
  Eigen::Isometry3d T_odom_cam = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Zero();  ///< of T_odom_cam, MRPT order
  std::vector<Eigen::Vector3d> points;     ///< odom frame, one per descriptor row
  cv::Mat descriptors;
  int baseline_tracked = -1;  ///< inliers of the first frame tracked after it
};

double rotationAngle(const Eigen::Isometry3d& T) {
  return Eigen::AngleAxisd(T.linear()).angle();
}

}  // namespace

struct VisualOdometry::Impl {
  VisualOdometryConfig config;
  cv::Ptr<cv::ORB> orb;
  std::deque<VoKeyframe> keyframes;
  // The local map: the last keyframes' points, rebuilt when a keyframe comes or goes.
  std::vector<Eigen::Vector3d> map_points;
  std::vector<int> map_keyframe;  ///< index into keyframes of each map point
  cv::Mat map_descriptors;

  TrackingState state = TrackingState::kNotStarted;
  int lost_frames = 0;
  Eigen::Isometry3d T_last = Eigen::Isometry3d::Identity(), T_prev = Eigen::Isometry3d::Identity();
  bool have_velocity = false;
  double last_stamp = std::numeric_limits<double>::quiet_NaN();
  // Where a (re)started map is anchored, and its uncertainty there (MRPT order).
  Eigen::Isometry3d T_anchor = Eigen::Isometry3d::Identity();
  Matrix6d anchor_cov = Matrix6d::Zero();
  Matrix6d last_cov = Matrix6d::Zero();  ///< MRPT order

  void rebuildLocalMap() {
    map_points.clear();
    map_keyframe.clear();
    std::vector<cv::Mat> rows;
    for (std::size_t k = 0; k < keyframes.size(); ++k) {
      const VoKeyframe& kf = keyframes[k];
      map_points.insert(map_points.end(), kf.points.begin(), kf.points.end());
      map_keyframe.insert(map_keyframe.end(), kf.points.size(), static_cast<int>(k));
      rows.push_back(kf.descriptors);
    }
    if (rows.empty()) {
      map_descriptors.release();
    } else {
      cv::vconcat(rows, map_descriptors);
    }
  }

  void addKeyframe(const Eigen::Isometry3d& T, const Matrix6d& cov_mrpt,
                   const std::vector<cv::KeyPoint>& kps, const cv::Mat& desc,
                   const std::vector<Eigen::Vector3d>& pts_cam, const std::vector<char>& has3d) {
    VoKeyframe kf;
    kf.T_odom_cam = T;
    kf.covariance = cov_mrpt;
    kf.covariance.diagonal().array() += 1e-12;  // keep it positive definite
    std::vector<int> rows;
    for (std::size_t i = 0; i < kps.size(); ++i) {
      if (!has3d[i]) continue;
      kf.points.push_back(T * pts_cam[i]);
      rows.push_back(static_cast<int>(i));
    }
    kf.descriptors = cv::Mat(static_cast<int>(rows.size()), desc.cols, desc.type());
    for (std::size_t r = 0; r < rows.size(); ++r)
      desc.row(rows[r]).copyTo(kf.descriptors.row(static_cast<int>(r)));
    keyframes.push_back(std::move(kf));
    while (static_cast<int>(keyframes.size()) > std::max(1, config.local_keyframes))
      keyframes.pop_front();
    rebuildLocalMap();
  }
};

VisualOdometry::VisualOdometry(const VisualOdometryConfig& config)
    : impl_(std::make_unique<Impl>()) {
  impl_->config = config;
  impl_->orb = cv::ORB::create(3 * config.features, static_cast<float>(config.scale_factor),
                               std::max(1, config.pyramid_levels), 19, 0, 2, cv::ORB::HARRIS_SCORE,
                               31, config.fast_threshold);
}

VisualOdometry::~VisualOdometry() = default;

const VisualOdometryConfig& VisualOdometry::config() const {
  return impl_->config;
}

int VisualOdometry::numKeyframes() const {
  return static_cast<int>(impl_->keyframes.size());
}

void VisualOdometry::reset(const Eigen::Isometry3d& T_odom_cam) {
  Impl& s = *impl_;
  s.keyframes.clear();
  s.rebuildLocalMap();
  s.state = TrackingState::kNotStarted;
  s.lost_frames = 0;
  s.have_velocity = false;
  s.T_last = s.T_prev = s.T_anchor = T_odom_cam;
  s.anchor_cov.setZero();
  s.last_cov.setZero();
  s.last_stamp = std::numeric_limits<double>::quiet_NaN();
}

VoFrameResult VisualOdometry::track(const GrayImageView& gray, const DepthImageView& depth,
                                    const PinholeIntrinsics& K, double stamp_s) {
  const auto t0 = std::chrono::steady_clock::now();
  Impl& s = *impl_;
  const VisualOdometryConfig& c = s.config;
  VoFrameResult out;
  auto finish = [&](VoFrameResult& r) -> VoFrameResult {
    r.state = s.state;
    r.time_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return r;
  };
  auto fail = [&](const std::string& why) -> VoFrameResult {
    out.pose_valid = false;
    out.problem = why;
    if (s.state == TrackingState::kTracking) s.state = TrackingState::kLost;
    if (s.state == TrackingState::kLost && ++s.lost_frames >= c.relocalise_frames &&
        !s.keyframes.empty()) {
      // Give up on the old map: the next good frame starts a new one where we last were, with
      // the uncertainty of an unknown motion added (the documented covariance jump).
      s.keyframes.clear();
      s.rebuildLocalMap();
      s.T_anchor = s.T_last;
      s.anchor_cov = s.last_cov;
      for (int i = 0; i < 3; ++i) {
        s.anchor_cov(i, i) += c.restart_sigma_position_m * c.restart_sigma_position_m;
        s.anchor_cov(i + 3, i + 3) += c.restart_sigma_rotation_rad * c.restart_sigma_rotation_rad;
      }
      s.have_velocity = false;
      out.problem += "; map dropped, restarting";
    }
    return finish(out);
  };

  // ---- Input checks.
  if (!gray.data || !depth.data || !K.valid() || gray.width != K.width || gray.height != K.height ||
      depth.width != K.width || depth.height != K.height) {
    return fail("image, depth and camera_info sizes disagree or an image is empty");
  }
  if (!std::isfinite(stamp_s)) return fail("non-finite stamp");

  // ---- Features, with depth where it is valid and not on a depth edge.
  const cv::Mat image(gray.height, gray.width, CV_8UC1, const_cast<std::uint8_t*>(gray.data),
                      gray.step > 0 ? static_cast<std::size_t>(gray.step)
                                    : static_cast<std::size_t>(cv::Mat::AUTO_STEP));
  std::vector<cv::KeyPoint> kps;
  cv::Mat desc;
  {
    // ORB keeps the strongest corners of the whole image, which crowd onto a few high-contrast
    // places; detect three times as many and keep the strongest of each cell of an 8 x 6 grid
    // first (as ORB-SLAM spreads its features), then the rest by strength.
    std::vector<cv::KeyPoint> all;
    s.orb->detect(image, all);
    const int gx = 8, gy = 6, quota = std::max(1, c.features / (gx * gy));
    std::vector<std::vector<cv::KeyPoint>> cells(gx * gy);
    for (const cv::KeyPoint& k : all) {
      const int x = std::clamp(static_cast<int>(k.pt.x * gx / gray.width), 0, gx - 1);
      const int y = std::clamp(static_cast<int>(k.pt.y * gy / gray.height), 0, gy - 1);
      cells[static_cast<std::size_t>(y * gx + x)].push_back(k);
    }
    std::vector<cv::KeyPoint> rest;
    auto stronger = [](const cv::KeyPoint& a, const cv::KeyPoint& b) {
      return a.response > b.response;
    };
    for (auto& cell : cells) {
      std::sort(cell.begin(), cell.end(), stronger);
      for (std::size_t i = 0; i < cell.size(); ++i)
        (static_cast<int>(i) < quota ? kps : rest).push_back(cell[i]);
    }
    std::sort(rest.begin(), rest.end(), stronger);
    for (std::size_t i = 0; i < rest.size() && static_cast<int>(kps.size()) < c.features; ++i)
      kps.push_back(rest[i]);
    if (!kps.empty()) s.orb->compute(image, kps, desc);
  }
  out.features = static_cast<int>(kps.size());
  std::vector<Eigen::Vector3d> pts_cam(kps.size());
  std::vector<char> has3d(kps.size(), 0);
  for (std::size_t i = 0; i < kps.size(); ++i) {
    const int u = static_cast<int>(std::lround(kps[i].pt.x)),
              v = static_cast<int>(std::lround(kps[i].pt.y));
    if (u < 1 || v < 1 || u >= depth.width - 1 || v >= depth.height - 1) continue;
    float lo = std::numeric_limits<float>::infinity(), hi = 0.f;
    bool all = true;
    for (int dv = -1; dv <= 1 && all; ++dv) {
      for (int du = -1; du <= 1; ++du) {
        const float z = depth.at(u + du, v + dv);
        if (!std::isfinite(z) || z <= 0.f) {
          all = false;
          break;
        }
        lo = std::min(lo, z), hi = std::max(hi, z);
      }
    }
    const float z = depth.at(u, v);
    if (!all || z < c.min_depth_m || z > c.max_depth_m || hi - lo > 0.03f * z) continue;
    pts_cam[i] = K.backProject(kps[i].pt.x, kps[i].pt.y, z);
    has3d[i] = 1;
    ++out.features_with_depth;
  }

  // ---- No map: start one here.
  if (s.keyframes.empty()) {
    if (out.features_with_depth < 2 * c.min_inliers) {
      return fail("too few features with depth (" + std::to_string(out.features_with_depth) +
                  ") to start");
    }
    s.addKeyframe(s.T_anchor, s.anchor_cov, kps, desc, pts_cam, has3d);
    out.restarted = true;
    out.keyframe = true;
    out.pose_valid = true;
    out.T_odom_cam = s.T_anchor;
    s.last_cov = s.anchor_cov;
    out.covariance = rosOrder(s.anchor_cov);
    s.T_last = s.T_prev = s.T_anchor;
    s.have_velocity = false;
    s.state = TrackingState::kTracking;
    s.lost_frames = 0;
    s.last_stamp = stamp_s;
    return finish(out);
  }
  if (out.features_with_depth < c.min_inliers || kps.empty()) {
    return fail("too few features with depth (" + std::to_string(out.features_with_depth) + ")");
  }

  // ---- 2D-3D matches to the local map.
  const bool lost = s.state != TrackingState::kTracking;
  const Eigen::Isometry3d T_pred =
      !lost && s.have_velocity ? s.T_last * (s.T_prev.inverse() * s.T_last) : s.T_last;
  std::vector<int> match_map(kps.size(), -1);  // frame feature -> map point
  auto guided = [&](double radius) {
    std::fill(match_map.begin(), match_map.end(), -1);
    std::vector<int> best_dist(kps.size(), std::numeric_limits<int>::max());
    const int cell = 16, gw = (K.width + cell - 1) / cell, gh = (K.height + cell - 1) / cell;
    std::vector<std::vector<int>> grid(static_cast<std::size_t>(gw * gh));
    for (std::size_t i = 0; i < kps.size(); ++i) {
      const int gx = std::clamp(static_cast<int>(kps[i].pt.x) / cell, 0, gw - 1);
      const int gy = std::clamp(static_cast<int>(kps[i].pt.y) / cell, 0, gh - 1);
      grid[static_cast<std::size_t>(gy * gw + gx)].push_back(static_cast<int>(i));
    }
    const Eigen::Isometry3d T_cam_odom = T_pred.inverse();
    const int r_cells = static_cast<int>(std::ceil(radius / cell));
    for (std::size_t m = 0; m < s.map_points.size(); ++m) {
      const Eigen::Vector3d p = T_cam_odom * s.map_points[m];
      if (p.z() < 0.1) continue;
      const Eigen::Vector2d uv = K.project(p);
      if (uv.x() < 0 || uv.y() < 0 || uv.x() >= K.width || uv.y() >= K.height) continue;
      const int gx = static_cast<int>(uv.x()) / cell, gy = static_cast<int>(uv.y()) / cell;
      int best = std::numeric_limits<int>::max(), second = best, best_i = -1;
      const uchar* md = s.map_descriptors.ptr<uchar>(static_cast<int>(m));
      for (int y = std::max(0, gy - r_cells); y <= std::min(gh - 1, gy + r_cells); ++y) {
        for (int x = std::max(0, gx - r_cells); x <= std::min(gw - 1, gx + r_cells); ++x) {
          for (int i : grid[static_cast<std::size_t>(y * gw + x)]) {
            const double du = kps[i].pt.x - uv.x(), dv = kps[i].pt.y - uv.y();
            if (du * du + dv * dv > radius * radius) continue;
            const int d = cv::hal::normHamming(md, desc.ptr<uchar>(i), desc.cols);
            if (d < best) {
              second = best, best = d, best_i = i;
            } else if (d < second) {
              second = d;
            }
          }
        }
      }
      if (best_i < 0 || best > c.max_descriptor_distance) continue;
      if (second != std::numeric_limits<int>::max() && best > c.ratio * second) continue;
      if (best < best_dist[best_i]) {
        best_dist[best_i] = best;
        match_map[best_i] = static_cast<int>(m);
      }
    }
  };
  auto count = [&]() {
    return static_cast<int>(
        std::count_if(match_map.begin(), match_map.end(), [](int m) { return m >= 0; }));
  };
  bool by_descriptor = false;
  if (!lost) {
    guided(c.match_radius_px);
    if (count() < 2 * c.min_inliers) guided(3.0 * c.match_radius_px);
  }
  if (lost || count() < c.min_inliers) {
    // Relocalisation: descriptors alone, against one keyframe at a time (the local map holds
    // each scene point once per keyframe, which would defeat the ratio test), newest first; the
    // keyframe with the most matches wins.
    by_descriptor = true;
    std::fill(match_map.begin(), match_map.end(), -1);
    cv::BFMatcher matcher(cv::NORM_HAMMING);
    std::size_t offset = s.map_points.size();
    for (std::size_t k = s.keyframes.size(); k-- > 0;) {
      const VoKeyframe& kf = s.keyframes[k];
      offset -= kf.points.size();
      if (kf.descriptors.empty()) continue;
      std::vector<std::vector<cv::DMatch>> knn;
      matcher.knnMatch(desc, kf.descriptors, knn, 2);
      std::vector<int> candidate(kps.size(), -1);
      std::vector<char> taken(kf.points.size(), 0);
      int n = 0;
      for (const auto& m : knn) {
        if (m.empty() || m[0].distance > c.max_descriptor_distance) continue;
        if (m.size() > 1 && m[0].distance > 0.8 * m[1].distance) continue;
        if (taken[static_cast<std::size_t>(m[0].trainIdx)]) continue;
        taken[static_cast<std::size_t>(m[0].trainIdx)] = 1;
        candidate[static_cast<std::size_t>(m[0].queryIdx)] =
            static_cast<int>(offset) + m[0].trainIdx;
        ++n;
      }
      if (n > count()) match_map = candidate;
    }
  }
  out.matches = count();
  if (out.matches < c.min_inliers) {
    return fail("too few matches to the map (" + std::to_string(out.matches) + ")");
  }

  // ---- PnP with RANSAC, then a robust refinement.
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image_pts;
  std::vector<int> feature_of;
  for (std::size_t i = 0; i < kps.size(); ++i) {
    if (match_map[i] < 0) continue;
    const Eigen::Vector3d& P = s.map_points[static_cast<std::size_t>(match_map[i])];
    object.emplace_back(static_cast<float>(P.x()), static_cast<float>(P.y()),
                        static_cast<float>(P.z()));
    image_pts.push_back(kps[i].pt);
    feature_of.push_back(static_cast<int>(i));
  }
  const cv::Matx33d camera(K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1);
  const double thr2 = c.ransac_reprojection_px * c.ransac_reprojection_px;
  // Inliers of a pose, the Gauss-Newton information of the fit, and per keyframe how many of
  // its points were tracked.
  auto evaluate = [&](const Eigen::Isometry3d& T_cam_odom, Matrix6d* H, std::vector<int>* tracked) {
    H->setZero();
    tracked->assign(s.keyframes.size(), 0);
    int inliers = 0;
    for (std::size_t k = 0; k < feature_of.size(); ++k) {
      const int i = feature_of[k];
      const int m = match_map[static_cast<std::size_t>(i)];
      const Eigen::Vector3d p = T_cam_odom * s.map_points[static_cast<std::size_t>(m)];
      if (p.z() < 0.05) continue;
      const Eigen::Vector2d e =
          K.project(p) - Eigen::Vector2d(kps[static_cast<std::size_t>(i)].pt.x,
                                         kps[static_cast<std::size_t>(i)].pt.y);
      if (e.squaredNorm() > thr2) continue;
      ++inliers;
      ++(*tracked)[static_cast<std::size_t>(s.map_keyframe[static_cast<std::size_t>(m)])];
      Eigen::Matrix<double, 2, 3> Jp;
      Jp << K.fx / p.z(), 0, -K.fx * p.x() / (p.z() * p.z()), 0, K.fy / p.z(),
          -K.fy * p.y() / (p.z() * p.z());
      Eigen::Matrix<double, 3, 6> Jx;
      Jx.leftCols<3>() = -Eigen::Matrix3d::Identity();
      Jx.rightCols<3>() << 0, -p.z(), p.y(), p.z(), 0, -p.x(), -p.y(), p.x(), 0;  // [p]x
      const Eigen::Matrix<double, 2, 6> J = Jp * Jx;
      *H += J.transpose() * J;
    }
    return inliers;
  };
  struct Fit {
    std::string problem;  ///< empty: a pose
    Eigen::Isometry3d T_cam_odom = Eigen::Isometry3d::Identity();
    int inliers = 0;
    Matrix6d H = Matrix6d::Zero();
    std::vector<int> tracked;
  };
  // One PnP: RANSAC (iterative from the prediction, or AP3P minimal sets), then a robust Ceres
  // refinement on RANSAC's inliers.
  auto attempt = [&](bool from_prediction) {
    Fit fit;
    const Eigen::Isometry3d T_guess = T_pred.inverse();
    const Eigen::AngleAxisd aa(T_guess.linear());
    cv::Vec3d rvec(aa.axis().x() * aa.angle(), aa.axis().y() * aa.angle(),
                   aa.axis().z() * aa.angle()),
        tvec(T_guess.translation().x(), T_guess.translation().y(), T_guess.translation().z());
    std::vector<int> ransac_inliers;
    bool solved = false;
    try {
      solved = cv::solvePnPRansac(
          object, image_pts, camera, cv::noArray(), rvec, tvec, from_prediction,
          c.ransac_iterations, static_cast<float>(c.ransac_reprojection_px), 0.99, ransac_inliers,
          from_prediction ? cv::SOLVEPNP_ITERATIVE : cv::SOLVEPNP_AP3P);
    } catch (const cv::Exception& e) {
      fit.problem = std::string("PnP failed: ") + e.what();
      return fit;
    }
    if (!solved || static_cast<int>(ransac_inliers.size()) < c.min_inliers) {
      fit.problem = "PnP found too few inliers (" + std::to_string(ransac_inliers.size()) + " of " +
                    std::to_string(out.matches) + ")";
      return fit;
    }
    const cv::Vec3d rv = rvec;
    const double angle = cv::norm(rv);
    Eigen::Quaterniond q = angle > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(
                                           angle, Eigen::Vector3d(rv[0], rv[1], rv[2]) / angle))
                                     : Eigen::Quaterniond::Identity();
    Eigen::Vector3d t(tvec[0], tvec[1], tvec[2]);
    Eigen::Isometry3d T_ransac = Eigen::Isometry3d::Identity();
    T_ransac.linear() = q.toRotationMatrix();
    T_ransac.translation() = t;
    ceres::Problem problem;
    for (int idx : ransac_inliers) {
      const int i = feature_of[static_cast<std::size_t>(idx)];
      const Eigen::Vector3d& P =
          s.map_points[static_cast<std::size_t>(match_map[static_cast<std::size_t>(i)])];
      if ((T_ransac * P).z() < 0.05) continue;  // behind the camera: no residual there
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<ReprojectionCost, 2, 4, 3>(
              new ReprojectionCost(P,
                                   Eigen::Vector2d(kps[static_cast<std::size_t>(i)].pt.x,
                                                   kps[static_cast<std::size_t>(i)].pt.y),
                                   K)),
          new ceres::HuberLoss(c.ransac_reprojection_px / 2.0), q.coeffs().data(), t.data());
    }
    if (problem.NumResidualBlocks() > 0) {
      problem.SetManifold(q.coeffs().data(), new ceres::EigenQuaternionManifold);
      ceres::Solver::Options options;
      options.linear_solver_type = ceres::DENSE_QR;
      options.max_num_iterations = 10;
      options.num_threads = 1;
      options.logging_type = ceres::SILENT;
      ceres::Solver::Summary summary;
      ceres::Solve(options, &problem, &summary);
      if (!summary.IsSolutionUsable() || !q.coeffs().allFinite() || !t.allFinite()) {
        q = Eigen::Quaterniond(T_ransac.linear());
        t = T_ransac.translation();
      }
    }
    fit.T_cam_odom.linear() = q.normalized().toRotationMatrix();
    fit.T_cam_odom.translation() = t;
    fit.inliers = evaluate(fit.T_cam_odom, &fit.H, &fit.tracked);
    Matrix6d H_r;
    std::vector<int> tracked_r;
    const int inliers_r = evaluate(T_ransac, &H_r, &tracked_r);
    if (inliers_r > fit.inliers + fit.inliers / 4) {  // the refinement failed: keep RANSAC's
      fit.inliers = inliers_r, fit.H = H_r, fit.tracked = tracked_r, fit.T_cam_odom = T_ransac;
    }
    if (fit.inliers < c.min_inliers)
      fit.problem = "too few inliers after refinement (" + std::to_string(fit.inliers) + ")";
    return fit;
  };
  Fit fit = attempt(!by_descriptor);
  if (!fit.problem.empty() && !by_descriptor) {
    Fit other = attempt(false);  // the prediction may have misled the iterative solver
    if (other.problem.empty() || other.inliers > fit.inliers) fit = other;
  }
  out.inliers = fit.inliers;
  if (!fit.problem.empty()) return fail(fit.problem);
  const Matrix6d& H = fit.H;
  const std::vector<int>& tracked = fit.tracked;
  const Eigen::Isometry3d T = fit.T_cam_odom.inverse();
  // An implausible jump is a failure, not motion (relocalisation is exempt: it is checked
  // against the map, not against the last pose).
  if (!lost && std::isfinite(s.last_stamp)) {
    const double dt = std::max(stamp_s - s.last_stamp, 1.0 / 30.0);
    const Eigen::Isometry3d step = s.T_last.inverse() * T;
    if (step.translation().norm() > c.max_speed_m_s * dt + 0.02 ||
        rotationAngle(step) > c.max_turn_rad_s * dt + 0.02) {
      return fail("implausible motion between frames");
    }
  }

  // ---- Uncertainty: the fit's covariance relative to the best-tracked keyframe, composed with
  // that keyframe's uncertain pose.
  const std::size_t ref =
      static_cast<std::size_t>(std::max_element(tracked.begin(), tracked.end()) - tracked.begin());
  const VoKeyframe& kref = s.keyframes[ref];
  const Eigen::Isometry3d T_rel = kref.T_odom_cam.inverse() * T;
  const Matrix6d cov_right =
      c.pixel_sigma * c.pixel_sigma * (H + 1e-9 * Matrix6d::Identity()).inverse();
  const mrpt::poses::CPose3DPDFGaussian rel(toMrpt(T_rel),
                                            toMrptMatrix(toMrptCovariance(T_rel, cov_right)));
  const mrpt::poses::CPose3DPDFGaussian pdf =
      mrpt::poses::CPose3DPDFGaussian(toMrpt(kref.T_odom_cam), toMrptMatrix(kref.covariance)) + rel;
  s.last_cov = fromMrpt(pdf.cov);

  out.pose_valid = true;
  out.relocalised = lost;
  out.T_odom_cam = T;
  out.covariance = rosOrder(s.last_cov);
  out.frame_covariance = cov_right;
  s.state = TrackingState::kTracking;
  s.lost_frames = 0;
  s.T_prev = lost ? T : s.T_last;
  s.T_last = T;
  s.have_velocity = !lost;
  s.last_stamp = stamp_s;

  // ---- A new keyframe when the newest one is tracked poorly or left behind.
  // Tracked share: inliers now against inliers on the first frame after the newest keyframe.
  VoKeyframe& newest = s.keyframes.back();
  if (newest.baseline_tracked < 0) newest.baseline_tracked = out.inliers;
  const Eigen::Isometry3d from_newest = newest.T_odom_cam.inverse() * T;
  const double share = static_cast<double>(out.inliers) / std::max(1, newest.baseline_tracked);
  if (share < c.keyframe_tracked_fraction ||
      from_newest.translation().norm() > c.keyframe_translation_m ||
      rotationAngle(from_newest) > c.keyframe_rotation_rad) {
    s.addKeyframe(T, s.last_cov, kps, desc, pts_cam, has3d);
    out.keyframe = true;
  }
  return finish(out);
}

}  // namespace geofusion
