#include "geofusion/odometry/visual_odometry.h"

#include "geofusion/common/ceres_compat.h"
#include "geofusion/common/pose_increment.h"
#include "geofusion/odometry/depth_alignment.h"
#include "geofusion/odometry/local_bundle_adjustment.h"

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
#include <unordered_map>
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

/// Covariance of right perturbations of T, expressed in MRPT's parameters of T (numeric
/// Jacobian; angles differenced with wrapping).
Matrix6d toMrptCovariance(const Eigen::Isometry3d& T, const Matrix6d& cov_right) {
  Matrix6d J;
  const double h = 1e-6;
  for (int i = 0; i < 6; ++i) {
    Vector6d d = Vector6d::Zero();
    d[i] = h;
    Vector6d diff = mrptVector(T * poseIncrement(d)) - mrptVector(T * poseIncrement(-d));
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

// A scene point of the local map, seen from one keyframe or more.
struct VoLandmark {
  Eigen::Vector3d X = Eigen::Vector3d::Zero();  ///< odom frame
};

// A keyframe's feature seen as a landmark.
struct VoObservation {
  long landmark = -1;  ///< -1: dropped (an outlier of the bundle adjustment)
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();
  double depth_m = 0.0;  ///< 0: none
  int level = 0;
};

struct VoKeyframe {
  Eigen::Isometry3d T_odom_cam = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Zero();  ///< of T_odom_cam, MRPT order
  std::vector<VoObservation> observations;
  cv::Mat descriptors;        ///< one row per observation
  int baseline_tracked = -1;  ///< inliers of the first frame tracked after it
};

double rotationAngle(const Eigen::Isometry3d& T) {
  return Eigen::AngleAxisd(T.linear()).angle();
}

// The features of one frame: ORB keypoints and descriptors, and the 3D point (camera frame) of
// each where the depth is valid and not on a depth edge.
struct VoFrame {
  std::vector<cv::KeyPoint> kps;
  cv::Mat desc;
  std::vector<Eigen::Vector3d> pts_cam;
  std::vector<char> has3d;
  int with_depth = 0;
};

// A PnP fit: the pose, its inliers and Gauss-Newton information, and per keyframe how many of its
// points were tracked.
struct VoFit {
  std::string problem;  ///< empty: a pose
  Eigen::Isometry3d T_cam_odom = Eigen::Isometry3d::Identity();
  int inliers = 0;
  Matrix6d H = Matrix6d::Zero();
  std::vector<int> tracked;
};

int matchCount(const std::vector<int>& match_map) {
  return static_cast<int>(
      std::count_if(match_map.begin(), match_map.end(), [](int m) { return m >= 0; }));
}

}  // namespace

struct VisualOdometry::Impl {
  VisualOdometryConfig config;
  cv::Ptr<cv::ORB> orb;
  std::deque<VoKeyframe> keyframes;
  std::unordered_map<long, VoLandmark> landmarks;
  long next_landmark = 0;
  // The local map: one row per keyframe observation (a landmark seen from several keyframes has
  // a row, and a descriptor, from each), rebuilt when a keyframe comes or goes.
  std::vector<Eigen::Vector3d> map_points;
  std::vector<int> map_keyframe;   ///< index into keyframes of each row
  std::vector<long> map_landmark;  ///< -1: a dropped observation (never matched)
  std::vector<int> keyframe_row;   ///< the first row of each keyframe
  cv::Mat map_descriptors;

  TrackingState state = TrackingState::kNotStarted;
  int lost_frames = 0;
  Eigen::Isometry3d T_last = Eigen::Isometry3d::Identity(), T_prev = Eigen::Isometry3d::Identity();
  bool have_velocity = false;
  double last_stamp = std::numeric_limits<double>::quiet_NaN();
  double prev_stamp = std::numeric_limits<double>::quiet_NaN();  ///< T_prev's
  // Where a (re)started map is anchored, and its uncertainty there (MRPT order).
  Eigen::Isometry3d T_anchor = Eigen::Isometry3d::Identity();
  Matrix6d anchor_cov = Matrix6d::Zero();
  Matrix6d last_cov = Matrix6d::Zero();  ///< MRPT order
  // The last placed frame's depth (a copy), the reference of the depth fallback.
  std::vector<float> ref_depth;
  int ref_width = 0, ref_height = 0;

  void rebuildLocalMap();

  // The steps of track(), in their order.
  void detectSpreadFeatures(const cv::Mat& image, VoFrame* f) const;
  void backProjectFeatures(const DepthImageView& depth, const PinholeIntrinsics& K,
                           VoFrame* f) const;
  void fail(const std::string& why, VoFrameResult* out);
  void startMap(const VoFrame& f, double stamp_s, VoFrameResult* out);
  std::vector<int> matchGuided(const VoFrame& f, const PinholeIntrinsics& K,
                               const Eigen::Isometry3d& T_pred, double radius) const;
  std::vector<int> matchByDescriptor(const VoFrame& f) const;
  int scorePose(const VoFrame& f, const std::vector<int>& match_map, const PinholeIntrinsics& K,
                const Eigen::Isometry3d& T_cam_odom, Matrix6d* H, std::vector<int>* tracked) const;
  VoFit solvePose(const VoFrame& f, const std::vector<int>& match_map, const PinholeIntrinsics& K,
                  const Eigen::Isometry3d& T_pred, bool from_prediction) const;
  Eigen::Isometry3d predictPose(double stamp_s) const;
  bool plausibleMotion(const Eigen::Isometry3d& T, double stamp_s) const;
  void recoverByDescriptor(const VoFrame& f, const PinholeIntrinsics& K,
                           const Eigen::Isometry3d& T_pred, double stamp_s, VoFit* fit,
                           std::vector<int>* match_map) const;
  Matrix6d composedCovariance(const VoFit& fit, const Eigen::Isometry3d& T,
                              Matrix6d* cov_right) const;
  bool placeByDepth(const DepthImageView& depth, const PinholeIntrinsics& K,
                    const Eigen::Isometry3d& T_pred, double stamp_s, Eigen::Isometry3d* T,
                    Matrix6d* cov_right, std::string* problem) const;
  void accept(const Eigen::Isometry3d& T, const Matrix6d& cov_mrpt, double stamp_s, bool lost,
              VoFrameResult* out);
  void rememberDepth(const DepthImageView& depth);
  bool needsKeyframe(const Eigen::Isometry3d& T, int inliers);

  void addKeyframe(const Eigen::Isometry3d& T, const Matrix6d& cov_mrpt, const VoFrame& f,
                   const std::vector<int>& match_map, const PinholeIntrinsics& K);
  void adjustLocalMap(const PinholeIntrinsics& K);
};

// The local map: every observation of the window's keyframes, at its landmark's position, with
// the keyframe's descriptor (each view of a scene point can be matched); landmarks no keyframe
// sees any more are forgotten.
void VisualOdometry::Impl::rebuildLocalMap() {
  map_points.clear();
  map_keyframe.clear();
  map_landmark.clear();
  keyframe_row.clear();
  std::unordered_map<long, char> seen;
  std::vector<cv::Mat> rows;
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    keyframe_row.push_back(static_cast<int>(map_points.size()));
    for (const VoObservation& o : keyframes[k].observations) {
      map_points.push_back(o.landmark < 0 ? Eigen::Vector3d::Zero() : landmarks.at(o.landmark).X);
      map_keyframe.push_back(static_cast<int>(k));
      map_landmark.push_back(o.landmark);
      seen[o.landmark] = 1;
    }
    rows.push_back(keyframes[k].descriptors);
  }
  for (auto it = landmarks.begin(); it != landmarks.end();)
    it = seen.count(it->first) ? std::next(it) : landmarks.erase(it);
  if (map_points.empty()) {
    map_descriptors.release();
  } else {
    cv::vconcat(rows, map_descriptors);
  }
}

// A new keyframe at T: the features matched to map points consistently with T (within the RANSAC
// threshold) become observations of those landmarks, the other features with depth new
// landmarks; the oldest keyframe beyond the window leaves, and the window is bundle-adjusted.
void VisualOdometry::Impl::addKeyframe(const Eigen::Isometry3d& T, const Matrix6d& cov_mrpt,
                                       const VoFrame& f, const std::vector<int>& match_map,
                                       const PinholeIntrinsics& K) {
  VoKeyframe kf;
  kf.T_odom_cam = T;
  kf.covariance = cov_mrpt;
  kf.covariance.diagonal().array() += 1e-12;  // keep it positive definite
  const Eigen::Isometry3d T_cam_odom = T.inverse();
  const double thr2 = config.ransac_reprojection_px * config.ransac_reprojection_px;
  std::vector<int> rows;
  std::unordered_map<long, char> seen;
  for (std::size_t i = 0; i < f.kps.size(); ++i) {
    const Eigen::Vector2d uv(f.kps[i].pt.x, f.kps[i].pt.y);
    VoObservation o{-1, uv, f.has3d[i] ? f.pts_cam[i].z() : 0.0, f.kps[i].octave};
    const int m = match_map.empty() ? -1 : match_map[i];
    if (m >= 0) {
      const Eigen::Vector3d p = T_cam_odom * map_points[static_cast<std::size_t>(m)];
      const long id = map_landmark[static_cast<std::size_t>(m)];
      if (id >= 0 && p.z() > 0.05 && (K.project(p) - uv).squaredNorm() <= thr2 && !seen.count(id))
        o.landmark = id;
    }
    if (o.landmark < 0 && f.has3d[i]) {
      o.landmark = next_landmark++;
      landmarks[o.landmark].X = T * f.pts_cam[i];
    }
    if (o.landmark < 0) continue;
    seen[o.landmark] = 1;
    kf.observations.push_back(o);
    rows.push_back(static_cast<int>(i));
  }
  kf.descriptors = cv::Mat(static_cast<int>(rows.size()), f.desc.cols, f.desc.type());
  for (std::size_t r = 0; r < rows.size(); ++r)
    f.desc.row(rows[r]).copyTo(kf.descriptors.row(static_cast<int>(r)));
  keyframes.push_back(std::move(kf));
  while (static_cast<int>(keyframes.size()) > std::max(1, config.local_keyframes))
    keyframes.pop_front();
  if (config.local_bundle_adjustment && keyframes.size() >= 2) adjustLocalMap(K);
  rebuildLocalMap();
}

// Local bundle adjustment of the window (the oldest keyframe fixed): poses and the landmarks seen
// from two keyframes or more; outlier observations dropped; the motion model moved with the
// newest keyframe (the current frame).
void VisualOdometry::Impl::adjustLocalMap(const PinholeIntrinsics& K) {
  std::unordered_map<long, int> count, point_of;
  for (const VoKeyframe& kf : keyframes)
    for (const VoObservation& o : kf.observations)
      if (o.landmark >= 0) ++count[o.landmark];
  std::vector<Eigen::Isometry3d> poses;
  std::vector<char> fixed;
  std::vector<Eigen::Vector3d> points;
  std::vector<long> point_landmark;
  std::vector<BundleObservation> observations;
  std::vector<std::pair<std::size_t, std::size_t>> source;  ///< keyframe, observation
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    poses.push_back(keyframes[k].T_odom_cam);
    fixed.push_back(k == 0);
    for (std::size_t j = 0; j < keyframes[k].observations.size(); ++j) {
      const VoObservation& o = keyframes[k].observations[j];
      if (o.landmark < 0 || count[o.landmark] < 2) continue;
      auto [it, added] = point_of.emplace(o.landmark, static_cast<int>(points.size()));
      if (added) {
        points.push_back(landmarks.at(o.landmark).X);
        point_landmark.push_back(o.landmark);
      }
      observations.push_back({static_cast<int>(k), it->second, o.uv, o.depth_m, o.level});
      source.emplace_back(k, j);
    }
  }
  LocalBundleAdjustmentOptions options;
  options.pixel_sigma = config.pixel_sigma;
  options.scale_factor = config.scale_factor;
  options.depth_sigma_per_m2 = config.ba_depth_sigma_per_m2;
  options.iterations = config.ba_iterations;
  std::vector<char> outlier;
  const BundleAdjustmentResult r =
      localBundleAdjustment(K, options, observations, fixed, &poses, &points, &outlier);
  if (!r.solved) return;  // the window keeps its poses: tracking goes on as without it
  const Eigen::Isometry3d correction = poses.back() * keyframes.back().T_odom_cam.inverse();
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    // A landmark only this keyframe sees (not adjusted) moves with it.
    const Eigen::Isometry3d moved = poses[k] * keyframes[k].T_odom_cam.inverse();
    for (const VoObservation& o : keyframes[k].observations)
      if (o.landmark >= 0 && count[o.landmark] == 1)
        landmarks.at(o.landmark).X = moved * landmarks.at(o.landmark).X;
    keyframes[k].T_odom_cam = poses[k];
  }
  for (std::size_t p = 0; p < points.size(); ++p) landmarks.at(point_landmark[p]).X = points[p];
  for (std::size_t i = 0; i < observations.size(); ++i)
    if (outlier[i]) keyframes[source[i].first].observations[source[i].second].landmark = -1;
  T_last = keyframes.back().T_odom_cam;
  T_prev = correction * T_prev;
}

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
  s.landmarks.clear();
  s.rebuildLocalMap();
  s.state = TrackingState::kNotStarted;
  s.lost_frames = 0;
  s.have_velocity = false;
  s.T_last = s.T_prev = s.T_anchor = T_odom_cam;
  s.anchor_cov.setZero();
  s.last_cov.setZero();
  s.last_stamp = std::numeric_limits<double>::quiet_NaN();
  s.ref_depth.clear();
}

// ORB keeps the strongest corners of the whole image, which crowd onto a few high-contrast
// places; detect three times as many and keep the strongest of each cell of an 8 x 6 grid first
// (as ORB-SLAM spreads its features), then the rest by strength.
void VisualOdometry::Impl::detectSpreadFeatures(const cv::Mat& image, VoFrame* f) const {
  std::vector<cv::KeyPoint> all;
  orb->detect(image, all);
  const int gx = 8, gy = 6, quota = std::max(1, config.features / (gx * gy));
  std::vector<std::vector<cv::KeyPoint>> cells(gx * gy);
  for (const cv::KeyPoint& k : all) {
    const int x = std::clamp(static_cast<int>(k.pt.x * gx / image.cols), 0, gx - 1);
    const int y = std::clamp(static_cast<int>(k.pt.y * gy / image.rows), 0, gy - 1);
    cells[static_cast<std::size_t>(y * gx + x)].push_back(k);
  }
  std::vector<cv::KeyPoint> rest;
  auto stronger = [](const cv::KeyPoint& a, const cv::KeyPoint& b) {
    return a.response > b.response;
  };
  for (auto& cell : cells) {
    std::sort(cell.begin(), cell.end(), stronger);
    for (std::size_t i = 0; i < cell.size(); ++i)
      (static_cast<int>(i) < quota ? f->kps : rest).push_back(cell[i]);
  }
  std::sort(rest.begin(), rest.end(), stronger);
  for (std::size_t i = 0; i < rest.size() && static_cast<int>(f->kps.size()) < config.features; ++i)
    f->kps.push_back(rest[i]);
  if (!f->kps.empty()) orb->compute(image, f->kps, f->desc);
}

// Back-projects each feature with its depth where the 3x3 neighbourhood is valid, within the
// depth range and not on a depth edge (spread under 3% of the depth).
void VisualOdometry::Impl::backProjectFeatures(const DepthImageView& depth,
                                               const PinholeIntrinsics& K, VoFrame* f) const {
  f->pts_cam.assign(f->kps.size(), Eigen::Vector3d::Zero());
  f->has3d.assign(f->kps.size(), 0);
  for (std::size_t i = 0; i < f->kps.size(); ++i) {
    const int u = static_cast<int>(std::lround(f->kps[i].pt.x)),
              v = static_cast<int>(std::lround(f->kps[i].pt.y));
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
    if (!all || z < config.min_depth_m || z > config.max_depth_m || hi - lo > 0.03f * z) continue;
    f->pts_cam[i] = K.backProject(f->kps[i].pt.x, f->kps[i].pt.y, z);
    f->has3d[i] = 1;
    ++f->with_depth;
  }
}

// Tracking failed at this frame: lost, and after `relocalise_frames` failures the old map is
// given up: the next good frame starts a new one where we last were, with the uncertainty of an
// unknown motion added (the documented covariance jump).
void VisualOdometry::Impl::fail(const std::string& why, VoFrameResult* out) {
  out->pose_valid = false;
  out->problem = why;
  if (state == TrackingState::kTracking) state = TrackingState::kLost;
  if (state == TrackingState::kLost && ++lost_frames >= config.relocalise_frames &&
      !keyframes.empty()) {
    keyframes.clear();
    landmarks.clear();
    rebuildLocalMap();
    T_anchor = T_last;
    anchor_cov = last_cov;
    for (int i = 0; i < 3; ++i) {
      anchor_cov(i, i) += config.restart_sigma_position_m * config.restart_sigma_position_m;
      anchor_cov(i + 3, i + 3) +=
          config.restart_sigma_rotation_rad * config.restart_sigma_rotation_rad;
    }
    have_velocity = false;
    out->problem += "; map dropped, restarting";
  }
}

// No map: the first keyframe of a new one, at the anchor.
void VisualOdometry::Impl::startMap(const VoFrame& f, double stamp_s, VoFrameResult* out) {
  addKeyframe(T_anchor, anchor_cov, f, {}, PinholeIntrinsics());
  out->restarted = true;
  out->keyframe = true;
  out->pose_valid = true;
  out->T_odom_cam = T_anchor;
  last_cov = anchor_cov;
  out->covariance = rosOrder(anchor_cov);
  T_last = T_prev = T_anchor;
  have_velocity = false;
  state = TrackingState::kTracking;
  lost_frames = 0;
  last_stamp = stamp_s;
}

// Guided matching: each local-map point projected with the predicted pose is matched to the
// frame features within `radius` pixels (Hamming distance, ratio test); each feature keeps its
// best map point. Returns frame feature -> map point (-1: none).
std::vector<int> VisualOdometry::Impl::matchGuided(const VoFrame& f, const PinholeIntrinsics& K,
                                                   const Eigen::Isometry3d& T_pred,
                                                   double radius) const {
  std::vector<int> match_map(f.kps.size(), -1);
  std::vector<int> best_dist(f.kps.size(), std::numeric_limits<int>::max());
  const int cell = 16, gw = (K.width + cell - 1) / cell, gh = (K.height + cell - 1) / cell;
  std::vector<std::vector<int>> grid(static_cast<std::size_t>(gw * gh));
  for (std::size_t i = 0; i < f.kps.size(); ++i) {
    const int gx = std::clamp(static_cast<int>(f.kps[i].pt.x) / cell, 0, gw - 1);
    const int gy = std::clamp(static_cast<int>(f.kps[i].pt.y) / cell, 0, gh - 1);
    grid[static_cast<std::size_t>(gy * gw + gx)].push_back(static_cast<int>(i));
  }
  const Eigen::Isometry3d T_cam_odom = T_pred.inverse();
  const int r_cells = static_cast<int>(std::ceil(radius / cell));
  for (std::size_t m = 0; m < map_points.size(); ++m) {
    if (map_landmark[m] < 0) continue;  // dropped by the bundle adjustment
    const Eigen::Vector3d p = T_cam_odom * map_points[m];
    if (p.z() < 0.1) continue;
    const Eigen::Vector2d uv = K.project(p);
    if (uv.x() < 0 || uv.y() < 0 || uv.x() >= K.width || uv.y() >= K.height) continue;
    const int gx = static_cast<int>(uv.x()) / cell, gy = static_cast<int>(uv.y()) / cell;
    int best = std::numeric_limits<int>::max(), second = best, best_i = -1;
    const uchar* md = map_descriptors.ptr<uchar>(static_cast<int>(m));
    for (int y = std::max(0, gy - r_cells); y <= std::min(gh - 1, gy + r_cells); ++y) {
      for (int x = std::max(0, gx - r_cells); x <= std::min(gw - 1, gx + r_cells); ++x) {
        for (int i : grid[static_cast<std::size_t>(y * gw + x)]) {
          const double du = f.kps[i].pt.x - uv.x(), dv = f.kps[i].pt.y - uv.y();
          if (du * du + dv * dv > radius * radius) continue;
          const int d = cv::hal::normHamming(md, f.desc.ptr<uchar>(i), f.desc.cols);
          if (d < best) {
            second = best, best = d, best_i = i;
          } else if (d < second) {
            second = d;
          }
        }
      }
    }
    if (best_i < 0 || best > config.max_descriptor_distance) continue;
    if (second != std::numeric_limits<int>::max() && best > config.ratio * second) continue;
    if (best < best_dist[best_i]) {
      best_dist[best_i] = best;
      match_map[best_i] = static_cast<int>(m);
    }
  }
  return match_map;
}

// Relocalisation: descriptors alone, against one keyframe at a time (its own features, a view
// of the scene the frame may share), newest first; the keyframe with the most matches wins.
std::vector<int> VisualOdometry::Impl::matchByDescriptor(const VoFrame& f) const {
  std::vector<int> match_map(f.kps.size(), -1);
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  for (std::size_t k = keyframes.size(); k-- > 0;) {
    const VoKeyframe& kf = keyframes[k];
    if (kf.descriptors.empty()) continue;
    std::vector<std::vector<cv::DMatch>> knn;
    matcher.knnMatch(f.desc, kf.descriptors, knn, 2);
    std::vector<int> candidate(f.kps.size(), -1);
    std::vector<char> taken(kf.observations.size(), 0);
    int n = 0;
    for (const auto& m : knn) {
      if (m.empty() || m[0].distance > config.max_descriptor_distance) continue;
      if (m.size() > 1 && m[0].distance > 0.8 * m[1].distance) continue;
      const std::size_t train = static_cast<std::size_t>(m[0].trainIdx);
      const long id = kf.observations[train].landmark;
      if (taken[train] || id < 0) continue;
      taken[train] = 1;
      candidate[static_cast<std::size_t>(m[0].queryIdx)] = keyframe_row[k] + m[0].trainIdx;
      ++n;
    }
    if (n > matchCount(match_map)) match_map = candidate;
  }
  return match_map;
}

// Inliers of a pose among the matches, the Gauss-Newton information of the fit, and per keyframe
// how many of its points were tracked.
int VisualOdometry::Impl::scorePose(const VoFrame& f, const std::vector<int>& match_map,
                                    const PinholeIntrinsics& K, const Eigen::Isometry3d& T_cam_odom,
                                    Matrix6d* H, std::vector<int>* tracked) const {
  const double thr2 = config.ransac_reprojection_px * config.ransac_reprojection_px;
  H->setZero();
  tracked->assign(keyframes.size(), 0);
  int inliers = 0;
  for (std::size_t i = 0; i < f.kps.size(); ++i) {
    const int m = match_map[i];
    if (m < 0) continue;
    const Eigen::Vector3d p = T_cam_odom * map_points[static_cast<std::size_t>(m)];
    if (p.z() < 0.05) continue;
    const Eigen::Vector2d e = K.project(p) - Eigen::Vector2d(f.kps[i].pt.x, f.kps[i].pt.y);
    if (e.squaredNorm() > thr2) continue;
    ++inliers;
    ++(*tracked)[static_cast<std::size_t>(map_keyframe[static_cast<std::size_t>(m)])];
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
}

// One PnP: RANSAC (iterative from the prediction, or AP3P minimal sets), then a robust Ceres
// refinement (Huber) on RANSAC's inliers; RANSAC's pose is kept when the refinement loses many
// inliers.
VoFit VisualOdometry::Impl::solvePose(const VoFrame& f, const std::vector<int>& match_map,
                                      const PinholeIntrinsics& K, const Eigen::Isometry3d& T_pred,
                                      bool from_prediction) const {
  const VisualOdometryConfig& c = config;
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image_pts;
  std::vector<int> feature_of;
  for (std::size_t i = 0; i < f.kps.size(); ++i) {
    if (match_map[i] < 0) continue;
    const Eigen::Vector3d& P = map_points[static_cast<std::size_t>(match_map[i])];
    object.emplace_back(static_cast<float>(P.x()), static_cast<float>(P.y()),
                        static_cast<float>(P.z()));
    image_pts.push_back(f.kps[i].pt);
    feature_of.push_back(static_cast<int>(i));
  }
  const cv::Matx33d camera(K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1);
  VoFit fit;
  const Eigen::Isometry3d T_guess = T_pred.inverse();
  const Eigen::AngleAxisd aa(T_guess.linear());
  cv::Vec3d rvec(aa.axis().x() * aa.angle(), aa.axis().y() * aa.angle(),
                 aa.axis().z() * aa.angle()),
      tvec(T_guess.translation().x(), T_guess.translation().y(), T_guess.translation().z());
  std::vector<int> ransac_inliers;
  bool solved = false;
  try {
    solved = cv::solvePnPRansac(object, image_pts, camera, cv::noArray(), rvec, tvec,
                                from_prediction, c.ransac_iterations,
                                static_cast<float>(c.ransac_reprojection_px), 0.99, ransac_inliers,
                                from_prediction ? cv::SOLVEPNP_ITERATIVE : cv::SOLVEPNP_AP3P);
  } catch (const cv::Exception& e) {
    fit.problem = std::string("PnP failed: ") + e.what();
    return fit;
  }
  if (!solved || static_cast<int>(ransac_inliers.size()) < c.min_inliers) {
    fit.problem = "PnP found too few inliers (" + std::to_string(ransac_inliers.size()) + " of " +
                  std::to_string(object.size()) + ")";
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
        map_points[static_cast<std::size_t>(match_map[static_cast<std::size_t>(i)])];
    if ((T_ransac * P).z() < 0.05) continue;  // behind the camera: no residual there
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<ReprojectionCost, 2, 4, 3>(
            new ReprojectionCost(P,
                                 Eigen::Vector2d(f.kps[static_cast<std::size_t>(i)].pt.x,
                                                 f.kps[static_cast<std::size_t>(i)].pt.y),
                                 K)),
        new ceres::HuberLoss(c.ransac_reprojection_px / 2.0), q.coeffs().data(), t.data());
  }
  if (problem.NumResidualBlocks() > 0) {
    ceres_compat::setManifold(&problem, q.coeffs().data(), new ceres_compat::QuaternionManifold);
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
  fit.inliers = scorePose(f, match_map, K, fit.T_cam_odom, &fit.H, &fit.tracked);
  Matrix6d H_r;
  std::vector<int> tracked_r;
  const int inliers_r = scorePose(f, match_map, K, T_ransac, &H_r, &tracked_r);
  if (inliers_r > fit.inliers + fit.inliers / 4) {  // the refinement failed: keep RANSAC's
    fit.inliers = inliers_r, fit.H = H_r, fit.tracked = tracked_r, fit.T_cam_odom = T_ransac;
  }
  if (fit.inliers < c.min_inliers)
    fit.problem = "too few inliers after refinement (" + std::to_string(fit.inliers) + ")";
  return fit;
}

// A frame the guided matches could not place, or placed implausibly far from the last pose (a
// repeated texture, matches locked onto a wrong pose), recovered against the keyframes' map by
// descriptors alone before the frame is given up: `fit` and `match_map` replaced when that
// succeeds with a plausible motion, else `fit`'s problem stands.
void VisualOdometry::Impl::recoverByDescriptor(const VoFrame& f, const PinholeIntrinsics& K,
                                               const Eigen::Isometry3d& T_pred, double stamp_s,
                                               VoFit* fit, std::vector<int>* match_map) const {
  std::vector<int> by_descriptor = matchByDescriptor(f);
  if (matchCount(by_descriptor) < config.min_inliers) return;
  VoFit again = solvePose(f, by_descriptor, K, T_pred, false);
  if (!again.problem.empty() || !plausibleMotion(again.T_cam_odom.inverse(), stamp_s)) return;
  *fit = std::move(again);
  *match_map = std::move(by_descriptor);
}

// The constant-velocity prediction for a frame at `stamp_s`: the last motion, scaled to the time
// since the last frame (a frame dropped on the way, by the driver or a busy node, doubles it).
Eigen::Isometry3d VisualOdometry::Impl::predictPose(double stamp_s) const {
  if (!have_velocity) return T_last;
  const Eigen::Isometry3d velocity = T_prev.inverse() * T_last;
  const double dt_last = last_stamp - prev_stamp, dt = stamp_s - last_stamp;
  const double scale =
      std::isfinite(dt_last) && dt_last > 1e-6 && std::isfinite(dt) ? dt / dt_last : 1.0;
  if (std::abs(scale - 1.0) < 0.05 || !(scale > 0.0)) return T_last * velocity;
  const Eigen::AngleAxisd turn(velocity.linear());
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  const double s = std::min(scale, 12.0);  // a long gap: at most twelve frames of motion ahead
  step.linear() = Eigen::AngleAxisd(s * turn.angle(), turn.axis()).toRotationMatrix();
  step.translation() = s * velocity.translation();
  return T_last * step;
}

// An implausible jump from the last pose is a failure, not motion.
bool VisualOdometry::Impl::plausibleMotion(const Eigen::Isometry3d& T, double stamp_s) const {
  if (!std::isfinite(last_stamp)) return true;
  const double dt = std::max(stamp_s - last_stamp, 1.0 / 30.0);
  const Eigen::Isometry3d step = T_last.inverse() * T;
  return step.translation().norm() <= config.max_speed_m_s * dt + 0.02 &&
         rotationAngle(step) <= config.max_turn_rad_s * dt + 0.02;
}

// The covariance of T (MRPT order): the uncertain pose T_base (MRPT order) composed with the
// motion from it to T, whose right-perturbation covariance is `cov_right`.
static Matrix6d composeUncertain(const Eigen::Isometry3d& T_base, const Matrix6d& cov_base,
                                 const Eigen::Isometry3d& T, const Matrix6d& cov_right) {
  const Eigen::Isometry3d T_rel = T_base.inverse() * T;
  const mrpt::poses::CPose3DPDFGaussian rel(toMrpt(T_rel),
                                            toMrptMatrix(toMrptCovariance(T_rel, cov_right)));
  const mrpt::poses::CPose3DPDFGaussian pdf =
      mrpt::poses::CPose3DPDFGaussian(toMrpt(T_base), toMrptMatrix(cov_base)) + rel;
  return fromMrpt(pdf.cov);
}

// The fit's covariance relative to the best-tracked keyframe, composed with that keyframe's
// uncertain pose (MRPT order); `cov_right` receives the fit's own covariance.
Matrix6d VisualOdometry::Impl::composedCovariance(const VoFit& fit, const Eigen::Isometry3d& T,
                                                  Matrix6d* cov_right) const {
  const std::size_t ref = static_cast<std::size_t>(
      std::max_element(fit.tracked.begin(), fit.tracked.end()) - fit.tracked.begin());
  const VoKeyframe& kref = keyframes[ref];
  *cov_right =
      config.pixel_sigma * config.pixel_sigma * (fit.H + 1e-9 * Matrix6d::Identity()).inverse();
  return composeUncertain(kref.T_odom_cam, kref.covariance, T, *cov_right);
}

// The depth fallback: the frame's depth aligned to the last placed frame's (ICP from the
// prediction); its pose and the fit's own covariance when the alignment is accepted, else why not.
bool VisualOdometry::Impl::placeByDepth(const DepthImageView& depth, const PinholeIntrinsics& K,
                                        const Eigen::Isometry3d& T_pred, double stamp_s,
                                        Eigen::Isometry3d* T, Matrix6d* cov_right,
                                        std::string* problem) const {
  if (ref_depth.empty() || ref_width != K.width || ref_height != K.height) {
    *problem = "no earlier depth to align to";
    return false;
  }
  DepthImageView ref;
  ref.data = ref_depth.data(), ref.width = ref_width, ref.height = ref_height;
  DepthAlignmentOptions o;
  o.min_depth_m = config.min_depth_m, o.max_depth_m = config.max_depth_m;
  o.max_rmse_m = config.depth_fallback_max_rmse_m;
  o.min_overlap = config.depth_fallback_min_overlap;
  o.min_constraint = config.depth_fallback_min_constraint;
  const DepthAlignment a = alignDepth(depth, ref, K, T_last.inverse() * T_pred, o);
  if (!a.aligned) {
    *problem = a.problem;
    return false;
  }
  *T = T_last * a.T_target_source;
  if (!plausibleMotion(*T, stamp_s)) {
    *problem = "implausible motion";
    return false;
  }
  *cov_right = (a.information + 1e-9 * Matrix6d::Identity()).inverse();
  return true;
}

// A placed frame: its pose and uncertainty reported, the motion model moved on.
void VisualOdometry::Impl::accept(const Eigen::Isometry3d& T, const Matrix6d& cov_mrpt,
                                  double stamp_s, bool lost, VoFrameResult* out) {
  last_cov = cov_mrpt;
  out->pose_valid = true;
  out->relocalised = lost;
  out->T_odom_cam = T;
  out->covariance = rosOrder(last_cov);
  state = TrackingState::kTracking;
  lost_frames = 0;
  T_prev = lost ? T : T_last;
  T_last = T;
  have_velocity = !lost;
  prev_stamp = last_stamp;
  last_stamp = stamp_s;
}

// The frame's depth kept as the next depth fallback's reference (only with the fallback on).
void VisualOdometry::Impl::rememberDepth(const DepthImageView& depth) {
  if (!config.depth_fallback) return;
  ref_width = depth.width, ref_height = depth.height;
  ref_depth.assign(depth.data, depth.data + static_cast<std::size_t>(depth.width) * depth.height);
}

// A new keyframe when the newest one is tracked poorly (inliers now against inliers on the first
// frame after it) or left behind.
bool VisualOdometry::Impl::needsKeyframe(const Eigen::Isometry3d& T, int inliers) {
  VoKeyframe& newest = keyframes.back();
  if (newest.baseline_tracked < 0) newest.baseline_tracked = inliers;
  const Eigen::Isometry3d from_newest = newest.T_odom_cam.inverse() * T;
  const double share = static_cast<double>(inliers) / std::max(1, newest.baseline_tracked);
  return share < config.keyframe_tracked_fraction ||
         from_newest.translation().norm() > config.keyframe_translation_m ||
         rotationAngle(from_newest) > config.keyframe_rotation_rad;
}

VoFrameResult VisualOdometry::track(const GrayImageView& gray, const DepthImageView& depth,
                                    const PinholeIntrinsics& K, double stamp_s) {
  const auto t0 = std::chrono::steady_clock::now();
  Impl& s = *impl_;
  const VisualOdometryConfig& c = s.config;
  VoFrameResult out;
  auto finish = [&]() -> VoFrameResult {
    out.state = s.state;
    out.time_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return out;
  };
  auto fail = [&](const std::string& why) {
    s.fail(why, &out);
    return finish();
  };
  if (!gray.data || !depth.data || !K.valid() || gray.width != K.width || gray.height != K.height ||
      depth.width != K.width || depth.height != K.height) {
    return fail("image, depth and camera_info sizes disagree or an image is empty");
  }
  if (!std::isfinite(stamp_s)) return fail("non-finite stamp");

  // Features with depth.
  const cv::Mat image(gray.height, gray.width, CV_8UC1, const_cast<std::uint8_t*>(gray.data),
                      gray.step > 0 ? static_cast<std::size_t>(gray.step)
                                    : static_cast<std::size_t>(cv::Mat::AUTO_STEP));
  VoFrame f;
  s.detectSpreadFeatures(image, &f);
  s.backProjectFeatures(depth, K, &f);
  out.features = static_cast<int>(f.kps.size());
  out.features_with_depth = f.with_depth;
  if (s.keyframes.empty()) {
    if (f.with_depth < 2 * c.min_inliers) {
      return fail("too few features with depth (" + std::to_string(f.with_depth) + ") to start");
    }
    s.startMap(f, stamp_s, &out);
    s.rememberDepth(depth);
    return finish();
  }
  const bool lost = s.state != TrackingState::kTracking;
  const Eigen::Isometry3d T_pred = lost ? s.T_last : s.predictPose(stamp_s);
  // A frame the features cannot place: by its depth (while tracking), else lost.
  auto fallBack = [&](const std::string& why) {
    Eigen::Isometry3d T;
    Matrix6d cov_right;
    std::string depth_problem = "depth fallback off";
    if (lost || !c.depth_fallback ||
        !s.placeByDepth(depth, K, T_pred, stamp_s, &T, &cov_right, &depth_problem))
      return fail(why + (lost ? "" : "; depth alignment: " + depth_problem));
    s.accept(T, composeUncertain(s.T_last, s.last_cov, T, cov_right), stamp_s, false, &out);
    out.frame_covariance = cov_right;
    out.by_depth = true;
    out.problem = why;
    // Its features (if any) anchor the next frames: a keyframe at the depth's pose.
    if (f.with_depth >= 2 * c.min_inliers) {
      s.addKeyframe(T, s.last_cov, f, {}, K);
      out.T_odom_cam = s.T_last;
      out.keyframe = true;
    }
    s.rememberDepth(depth);
    return finish();
  };
  if (f.with_depth < c.min_inliers || f.kps.empty()) {
    return fallBack("too few features with depth (" + std::to_string(f.with_depth) + ")");
  }

  // 2D-3D matches to the local map: guided by the constant-velocity prediction, by descriptors
  // alone when lost or when guidance finds too few.
  std::vector<int> match_map(f.kps.size(), -1);
  if (!lost) {
    match_map = s.matchGuided(f, K, T_pred, c.match_radius_px);
    if (matchCount(match_map) < 2 * c.min_inliers)
      match_map = s.matchGuided(f, K, T_pred, 3.0 * c.match_radius_px);
  }
  const bool by_descriptor = lost || matchCount(match_map) < c.min_inliers;
  if (by_descriptor) match_map = s.matchByDescriptor(f);
  out.matches = matchCount(match_map);
  if (out.matches < c.min_inliers) {
    return fallBack("too few matches to the map (" + std::to_string(out.matches) + ")");
  }

  // The pose: PnP from the prediction, else from minimal sets (the prediction may have misled the
  // iterative solver).
  VoFit fit = s.solvePose(f, match_map, K, T_pred, !by_descriptor);
  if (!fit.problem.empty() && !by_descriptor) {
    VoFit other = s.solvePose(f, match_map, K, T_pred, false);
    if (other.problem.empty() || other.inliers > fit.inliers) fit = other;
  }
  // Relocalisation is exempt from the motion check: it is checked against the map.
  if (fit.problem.empty() && !lost && !s.plausibleMotion(fit.T_cam_odom.inverse(), stamp_s))
    fit.problem = "implausible motion between frames";
  if (!fit.problem.empty() && !by_descriptor)
    s.recoverByDescriptor(f, K, T_pred, stamp_s, &fit, &match_map);
  out.inliers = fit.inliers;
  if (!fit.problem.empty()) return fallBack(fit.problem);
  const Eigen::Isometry3d T = fit.T_cam_odom.inverse();

  // Tracked: the pose, its uncertainty, the motion model.
  Matrix6d cov_right;
  s.accept(T, s.composedCovariance(fit, T, &cov_right), stamp_s, lost, &out);
  out.frame_covariance = cov_right;
  if (s.needsKeyframe(T, out.inliers)) {
    s.addKeyframe(T, s.last_cov, f, match_map, K);
    out.T_odom_cam = s.T_last;  // the bundle adjustment's pose of this frame
    out.keyframe = true;
  }
  s.rememberDepth(depth);
  return finish();
}

}  // namespace geofusion
