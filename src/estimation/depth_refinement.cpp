#include "geofusion/estimation/depth_refinement.h"

#include "geofusion/model/object_model.h"
#include "geofusion/render/renderer.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace geofusion {

const char* toString(RefinementOutcome outcome) {
  switch (outcome) {
    case RefinementOutcome::kAccepted: return "accepted";
    case RefinementOutcome::kTooFewPoints: return "too_few_points";
    case RefinementOutcome::kBeyondGuard: return "beyond_guard";
    case RefinementOutcome::kNotConverged: return "not_converged";
    case RefinementOutcome::kNoImprovement: return "no_improvement";
    default: return "not_attempted";
  }
}

bool parseRefinementOutcome(const std::string& name, RefinementOutcome* outcome) {
  for (RefinementOutcome o :
       {RefinementOutcome::kNotAttempted, RefinementOutcome::kAccepted,
        RefinementOutcome::kTooFewPoints, RefinementOutcome::kBeyondGuard,
        RefinementOutcome::kNotConverged, RefinementOutcome::kNoImprovement}) {
    if (name == toString(o)) {
      *outcome = o;
      return true;
    }
  }
  return false;
}

Eigen::Matrix3d rayAlignedSqrtInformation(const Eigen::Vector3d& position_cam, double ray_sigma,
                                          double lateral_sigma) {
  const double norm = position_cam.norm();
  const Eigen::Vector3d ray =
      norm > 1e-9 ? Eigen::Vector3d(position_cam / norm) : Eigen::Vector3d::UnitZ();
  const Eigen::Matrix3d along = ray * ray.transpose();
  return along / ray_sigma + (Eigen::Matrix3d::Identity() - along) / lateral_sigma;
}

namespace {

// A point of the model's visible surface with its outward normal, in the model frame.
struct SurfacePoint {
  Eigen::Vector3d p, n;
};

// The visible surface of a rendering: a grid of at most `max_points` rendered pixels, each with
// the normal of the rendered depth around it (pixels at a silhouette or a depth step are left
// out), brought into the model frame.
std::vector<SurfacePoint> sampleVisibleSurface(const RenderedImages& rendered,
                                               const PinholeIntrinsics& K,
                                               const Eigen::Isometry3d& T_cam_obj, int max_points) {
  const PixelBox& box = rendered.region;
  int count = 0;
  for (float z : rendered.depth) count += z > 0.f;
  const int stride = std::max(
      1, static_cast<int>(std::ceil(std::sqrt(count / std::max(1.0, double(max_points))))));
  auto depthAt = [&](int x, int y) {
    if (x < 0 || y < 0 || x >= box.width || y >= box.height) return 0.f;
    return rendered.depth[static_cast<std::size_t>(y) * box.width + x];
  };
  auto point = [&](int x, int y) {
    return K.backProject(box.x + x, box.y + y, depthAt(x, y));  // pixel centres at integers
  };
  const Eigen::Isometry3d T_obj_cam = T_cam_obj.inverse();
  std::vector<SurfacePoint> out;
  for (int y = stride / 2; y < box.height; y += stride) {
    for (int x = stride / 2; x < box.width; x += stride) {
      const float z = depthAt(x, y);
      if (!(z > 0.f)) continue;
      const int b = 2;  // normal baseline, pixels
      const float zl = depthAt(x - b, y), zr = depthAt(x + b, y), zu = depthAt(x, y - b),
                  zd = depthAt(x, y + b);
      const float step = 0.01f;
      if (!(zl > 0.f && zr > 0.f && zu > 0.f && zd > 0.f) || std::abs(zl - z) > step ||
          std::abs(zr - z) > step || std::abs(zu - z) > step || std::abs(zd - z) > step)
        continue;
      const Eigen::Vector3d p = point(x, y);
      Eigen::Vector3d n =
          (point(x + 1, y) - point(x - 1, y)).cross(point(x, y + 1) - point(x, y - 1));
      if (!(n.norm() > 1e-12)) continue;
      n.normalize();
      if (n.dot(p) > 0) n = -n;  // towards the camera
      out.push_back({T_obj_cam * p, T_obj_cam.linear() * n});
    }
  }
  return out;
}

// Signed distance along the pixel's ray from the model point p (camera frame) to the observed
// surface (positive: observed behind it); NaN without an observed depth there.
double alongRay(const Eigen::Vector3d& p, const DepthImageView& depth, const PinholeIntrinsics& K,
                Eigen::Vector3d* observed = nullptr) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!(p.z() > 0.01)) return nan;
  const Eigen::Vector2d uv = K.project(p);
  int u, v;
  if (!K.nearestPixel(uv, &u, &v) || u >= depth.width || v >= depth.height) return nan;
  const float z = depth.at(u, v);
  if (!(z > 0.f) || !std::isfinite(z)) return nan;
  if (observed) *observed = K.backProject(u, v, z);
  return distanceAlongRay(K, uv.x(), uv.y(), z, p.z());
}

// Where most of the visible surface meets the observed one along the ray: the centre of the
// densest window of the per-point distances (occluders in front and background behind spread
// out; the object's own surface is one cluster). NaN with fewer than `min_points` distances.
double dominantRayOffset(const std::vector<SurfacePoint>& points, const Eigen::Isometry3d& T,
                         const DepthImageView& depth, const PinholeIntrinsics& K, double window,
                         int min_points) {
  std::vector<double> d;
  for (const SurfacePoint& s : points) {
    const double a = alongRay(T * s.p, depth, K);
    if (std::isfinite(a)) d.push_back(a);
  }
  if (static_cast<int>(d.size()) < std::max(1, min_points))
    return std::numeric_limits<double>::quiet_NaN();
  std::sort(d.begin(), d.end());
  std::size_t best_lo = 0, best_hi = 0, hi = 0;
  for (std::size_t lo = 0; lo < d.size(); ++lo) {
    while (hi < d.size() && d[hi] - d[lo] <= window) ++hi;
    if (hi - lo > best_hi - best_lo) best_lo = lo, best_hi = hi;
  }
  double sum = 0.0;
  for (std::size_t i = best_lo; i < best_hi; ++i) sum += d[i];
  return sum / static_cast<double>(best_hi - best_lo);
}

// The rotation increments allowed in the model frame: all three axes, or the two across a
// continuous symmetry axis (rotating about it is invisible to depth: the axis stays free).
Eigen::MatrixXd rotationBasis(const ObjectModel& model) {
  if (model.symmetry.type != Symmetry::Type::kContinuous) return Eigen::Matrix3d::Identity();
  const Eigen::Vector3d a = model.symmetry.axis.normalized();
  const Eigen::Vector3d b1 = a.unitOrthogonal(), b2 = a.cross(b1);
  Eigen::MatrixXd B(3, 2);
  B << b1, b2;
  return B;
}

struct IcpStep {
  int points = 0;
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();  ///< model frame, rotation vector
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

// One round of projective point-to-plane ICP: each model point meets the observed point on its
// pixel; gated, Cauchy-weighted Gauss-Newton step on the rotation (model frame, in `basis`) and
// the translation (camera frame). The detection T0 is a prior (the detector's rotation and lateral
// uncertainty, none along the ray): directions the visible surface cannot fix (a single face seen
// head-on) stay where the detector put them.
IcpStep icpRound(const std::vector<SurfacePoint>& points, const Eigen::Isometry3d& T,
                 const Eigen::Isometry3d& T0, const DepthImageView& depth,
                 const PinholeIntrinsics& K, const Eigen::MatrixXd& basis,
                 const DepthRefinementConfig& config) {
  const Eigen::Index k = basis.cols(), n = k + 3;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
  IcpStep step;
  Eigen::VectorXd J(n);
  for (const SurfacePoint& s : points) {
    const Eigen::Vector3d p = T * s.p;
    Eigen::Vector3d q;
    if (!std::isfinite(alongRay(p, depth, K, &q))) continue;
    const Eigen::Vector3d normal = T.linear() * s.n;
    const double r = normal.dot(p - q);
    if (std::abs(r) > config.gate_m || (p - q).norm() > 2.0 * config.gate_m) continue;
    const double w = 1.0 / (1.0 + (r / config.loss_scale_m) * (r / config.loss_scale_m));
    J.head(k) = basis.transpose() * s.p.cross(s.n);
    J.tail(3) = normal;
    H += w * J * J.transpose();
    g += w * r * J;
    ++step.points;
  }
  if (step.points < config.min_points) return step;
  // The prior, in the data's units (residuals of loss_scale_m).
  const Eigen::AngleAxisd turned(T0.linear().transpose() * T.linear());
  const Eigen::Vector3d ray = T0.translation().normalized();
  const Eigen::Matrix3d lateral = Eigen::Matrix3d::Identity() - ray * ray.transpose();
  const double h_rot = std::pow(config.loss_scale_m / config.prior_sigma_rotation_rad, 2);
  const double h_lat = std::pow(config.loss_scale_m / config.prior_sigma_lateral_m, 2);
  H.topLeftCorner(k, k) += h_rot * Eigen::MatrixXd::Identity(k, k);
  g.head(k) += h_rot * basis.transpose() * (turned.angle() * turned.axis());
  H.bottomRightCorner(3, 3) += h_lat * lateral;
  g.tail(3) += h_lat * lateral * (T.translation() - T0.translation());
  // Levenberg-Marquardt damping: projective correspondences change from round to round.
  Eigen::MatrixXd damped = H;
  damped.diagonal() *= 1.0 + config.damping;
  damped.diagonal().array() += 1e-12;
  const Eigen::VectorXd x = damped.ldlt().solve(-g);
  if (!x.allFinite()) {
    step.points = 0;
    return step;
  }
  step.rotation = basis * x.head(k);
  step.translation = x.tail(3);
  return step;
}

Eigen::Isometry3d applyStep(const Eigen::Isometry3d& T, const IcpStep& step) {
  Eigen::Isometry3d out = T;
  const double angle = step.rotation.norm();
  if (angle > 0)
    out.linear() = T.linear() * Eigen::AngleAxisd(angle, step.rotation / angle).toRotationMatrix();
  out.translation() += step.translation;
  return out;
}

double rotationAngle(const Eigen::Matrix3d& R) {
  return Eigen::AngleAxisd(R).angle();
}

}  // namespace

bool improves(const ConsistencyResult& before, const ConsistencyResult& after,
              const DepthRefinementConfig& config) {
  if (!after.determined) return false;
  // The inlier ratio counts only the points nothing hides: with almost all of them hidden (a
  // pose behind the observed surface) it is the ratio of a few points and says nothing; the
  // score, whose occlusion term sees the pose sunk behind the surface, judges then.
  auto r_in_defined = [&](const ConsistencyResult& r) {
    const int observed = r.rendered - r.missing;
    return r.determined && observed > 0 &&
           r.inliers + r.outliers + r.uncertain >= config.min_visible_share * observed;
  };
  if (!r_in_defined(before) || !r_in_defined(after)) return after.score > before.score;
  return after.r_in > before.r_in + config.min_inlier_gain;
}

DepthRefiner::DepthRefiner(ConsistencyScorer* scorer, const DepthRefinementConfig& config)
    : scorer_(scorer), config_(config) {}

DepthRefinement DepthRefiner::refine(const std::shared_ptr<const ObjectModel>& model,
                                     const Eigen::Isometry3d& T_cam_obj,
                                     const DepthImageView& depth, const PinholeIntrinsics& K) {
  DepthRefinement out;
  out.T_cam_obj = T_cam_obj;
  out.ray_offset_m = std::numeric_limits<double>::quiet_NaN();
  const RenderedImages* rendered = depth.data ? scorer_->render(model, T_cam_obj, K) : nullptr;
  if (!rendered) {
    out.before = out.after = undeterminedResult(scorer_->config());
    return out;
  }
  out.before = out.after = compareDepth(*rendered, depth, K, scorer_->config());
  const std::vector<SurfacePoint> surface =
      sampleVisibleSurface(*rendered, K, T_cam_obj, config_.max_points);
  out.ray_offset_m =
      dominantRayOffset(surface, T_cam_obj, depth, K, config_.ray_window_m, config_.min_points);
  if (!config_.enabled) return out;
  if (!std::isfinite(out.ray_offset_m)) {
    out.outcome = RefinementOutcome::kTooFewPoints;
    return out;
  }
  if (std::abs(out.ray_offset_m) > config_.max_translation_m) {
    out.correction_translation_m = std::abs(out.ray_offset_m);
    out.outcome = RefinementOutcome::kBeyondGuard;
    return out;
  }
  // Onto the observed surface along the ray, then ICP for the rest.
  Eigen::Isometry3d T = T_cam_obj;
  T.translation() += out.ray_offset_m * T.translation().normalized();
  const Eigen::MatrixXd basis = rotationBasis(*model);
  bool converged = false;
  for (int round = 0; round < config_.iterations && !converged; ++round) {
    const IcpStep step = icpRound(surface, T, T_cam_obj, depth, K, basis, config_);
    out.points = step.points;
    if (step.points < config_.min_points) {
      out.outcome = RefinementOutcome::kTooFewPoints;
      return out;
    }
    T = applyStep(T, step);
    converged = step.translation.norm() < config_.converged_translation_m &&
                step.rotation.norm() < config_.converged_rotation_rad;
  }
  out.correction_translation_m = (T.translation() - T_cam_obj.translation()).norm();
  out.correction_rotation_rad = rotationAngle(T_cam_obj.linear().transpose() * T.linear());
  if (out.correction_translation_m > config_.max_translation_m ||
      out.correction_rotation_rad > config_.max_rotation_rad) {
    out.outcome = RefinementOutcome::kBeyondGuard;
    return out;
  }
  if (!converged) {
    out.outcome = RefinementOutcome::kNotConverged;
    return out;
  }
  // Scored from the first rendering, moved (one render a detection).
  const ConsistencyResult refined =
      compareMovedDepth(*rendered, T * T_cam_obj.inverse(), depth, K, scorer_->config());
  if (!improves(out.before, refined, config_)) {
    out.outcome = RefinementOutcome::kNoImprovement;
    return out;
  }
  out.outcome = RefinementOutcome::kAccepted;
  out.T_cam_obj = T;
  out.after = refined;
  return out;
}

}  // namespace geofusion
