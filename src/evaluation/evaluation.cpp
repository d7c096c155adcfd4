#include "geofusion/evaluation/evaluation.h"

#include "geofusion/estimation/frame_by_frame.h"
#include "geofusion/evaluation/metrics.h"

#include <cmath>
#include <string>

namespace geofusion {

Keyframe makeKeyframe(const FramePose& pose, const SequenceFrame& frame,
                      const PinholeIntrinsics& K) {
  Keyframe kf;
  kf.stamp_s = pose.stamp_s;
  kf.K = K;
  kf.T_odom_cam = pose.T_odom_base * pose.T_base_link * RobotGeometry::cameraLinkToOptical();
  if (frame.images.depth.size() == static_cast<std::size_t>(K.width) * K.height) {
    kf.depth = DepthImageView{frame.images.depth.data(), K.width, K.height};
  }
  const FrameByFrame checker;
  for (const RawDetection& raw : frame.detections) {
    ObjectMeasurement m;
    SkipReason why;
    if (checker.check(raw, &m, &why)) kf.detections.push_back(m);
  }
  return kf;
}

MapScore scoreMap(const ClutterScene& scene, const std::vector<ObjectEstimate>& objects,
                  double max_adds_m) {
  MapScore sc;
  std::vector<bool> taken(scene.objects.size(), false);
  for (const ObjectEstimate& o : objects) {
    ++sc.objects;
    double best = 1e9;
    int best_i = -1;
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
      if (taken[i] || !o.model || !scene.objects[i].presentAtTheEnd() ||
          scene.objects[i].model->name != o.model->name)
        continue;
      const double e = addsError(o.model->points, o.T_map_obj, scene.objects[i].T_world_obj);
      if (e < best) best = e, best_i = static_cast<int>(i);
    }
    if (best_i >= 0 && best < max_adds_m) {
      taken[static_cast<std::size_t>(best_i)] = true;
      sc.match.push_back(best_i);
      ++sc.true_positives;
      sc.adds_m.push_back(best);
      sc.mean_adds_m += best;
    } else {
      ++sc.false_positives;
      sc.match.push_back(-1);
    }
  }
  if (sc.true_positives) sc.mean_adds_m /= sc.true_positives;
  return sc;
}

namespace {

// Map objects (positions, class names) and the scene's objects present at the end.
struct AlignmentPoints {
  std::vector<Eigen::Vector3d> est, truth;
  std::vector<std::string> est_class, true_class;
};

// The map objects within inlier_m of a scene object of their class under T (nearest one each):
// their positions and the matched scene positions, and the sum of squared residuals.
int alignmentInliers(const AlignmentPoints& p, const Eigen::Isometry3d& T, double inlier_m,
                     std::vector<Eigen::Vector3d>* est, std::vector<Eigen::Vector3d>* truth,
                     double* sq_sum) {
  int n = 0;
  *sq_sum = 0.0;
  for (std::size_t i = 0; i < p.est.size(); ++i) {
    const Eigen::Vector3d x = T * p.est[i];
    double best = inlier_m;
    int best_j = -1;
    for (std::size_t j = 0; j < p.truth.size(); ++j) {
      const double d = (p.truth[j] - x).norm();
      if (p.true_class[j] == p.est_class[i] && d < best) best = d, best_j = static_cast<int>(j);
    }
    if (best_j < 0) continue;
    ++n;
    *sq_sum += best * best;
    if (est) est->push_back(p.est[i]), truth->push_back(p.truth[static_cast<std::size_t>(best_j)]);
  }
  return n;
}

// The planar motion (turn about z, then shift) that maps est points a, b onto true points c, d.
Eigen::Isometry3d planarFromPairs(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                  const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  const Eigen::Vector3d u = b - a, v = d - c;
  const double yaw = std::atan2(v.y(), v.x()) - std::atan2(u.y(), u.x());
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = 0.5 * (c + d) - T.linear() * 0.5 * (a + b);
  return T;
}

// Least squares planar motion (turn about z, shift) of est onto truth: 2-D Procrustes on x, y
// and the mean height difference. (A full 3-D fit tilts on a table's nearly coplanar objects.)
Eigen::Isometry3d planarFit(const std::vector<Eigen::Vector3d>& est,
                            const std::vector<Eigen::Vector3d>& truth) {
  Eigen::Vector3d me = Eigen::Vector3d::Zero(), mt = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < est.size(); ++i) me += est[i], mt += truth[i];
  me /= static_cast<double>(est.size());
  mt /= static_cast<double>(est.size());
  double sin_sum = 0.0, cos_sum = 0.0;
  for (std::size_t i = 0; i < est.size(); ++i) {
    const Eigen::Vector2d a = (est[i] - me).head<2>(), b = (truth[i] - mt).head<2>();
    cos_sum += a.dot(b);
    sin_sum += a.x() * b.y() - a.y() * b.x();
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() =
      Eigen::AngleAxisd(std::atan2(sin_sum, cos_sum), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = mt - T.linear() * me;
  return T;
}

}  // namespace

SceneAlignment alignMapToScene(const ClutterScene& scene,
                               const std::vector<ObjectEstimate>& objects, double inlier_m) {
  AlignmentPoints p;
  for (const ObjectEstimate& o : objects) {
    if (!o.model) continue;
    p.est.push_back(o.T_map_obj.translation());
    p.est_class.push_back(o.model->name);
  }
  for (const SceneObject& t : scene.objects) {
    if (!t.presentAtTheEnd()) continue;
    p.truth.push_back(t.T_world_obj.translation());
    p.true_class.push_back(t.model->name);
  }
  SceneAlignment best;
  double best_sq = 0.0;
  const std::size_t n = p.est.size(), m = p.truth.size();
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = a + 1; b < n; ++b) {
      const double dab = (p.est[b] - p.est[a]).head<2>().norm();
      if (dab < 2.0 * inlier_m) continue;  // too close to tell the turn
      for (std::size_t c = 0; c < m; ++c) {
        if (p.true_class[c] != p.est_class[a]) continue;
        for (std::size_t d = 0; d < m; ++d) {
          if (d == c || p.true_class[d] != p.est_class[b] ||
              std::abs((p.truth[d] - p.truth[c]).head<2>().norm() - dab) > 2.0 * inlier_m)
            continue;
          const Eigen::Isometry3d T = planarFromPairs(p.est[a], p.est[b], p.truth[c], p.truth[d]);
          double sq = 0.0;
          const int k = alignmentInliers(p, T, inlier_m, nullptr, nullptr, &sq);
          if (k > best.inliers || (k == best.inliers && k > 0 && sq < best_sq))
            best.inliers = k, best_sq = sq, best.T_true_map = T;
        }
      }
    }
  }
  if (best.inliers < 2) return SceneAlignment();
  // Refined on the inliers (twice: the refined transform may gather one more).
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<Eigen::Vector3d> est, truth;
    double sq = 0.0;
    const int k = alignmentInliers(p, best.T_true_map, inlier_m, &est, &truth, &sq);
    if (k < 3) break;
    const Eigen::Isometry3d T = planarFit(est, truth);
    std::vector<Eigen::Vector3d> e2, t2;
    double sq2 = 0.0;
    const int k2 = alignmentInliers(p, T, inlier_m, &e2, &t2, &sq2);
    if (k2 < k || (k2 == k && sq2 >= sq)) break;
    best.T_true_map = T;
  }
  double sq = 0.0;
  best.inliers = alignmentInliers(p, best.T_true_map, inlier_m, nullptr, nullptr, &sq);
  best.rmse_m = best.inliers > 0 ? std::sqrt(sq / best.inliers) : 0.0;
  return best;
}

int objectsDetectedInFrames(const ClutterScene& scene, const std::vector<SequenceFrame>& frames,
                            int min_frames) {
  int n = 0;
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    int seen = 0;
    for (const auto& f : frames) {
      for (std::size_t d = 0; d < f.detection_truth.size(); ++d) {
        seen += f.detection_truth[d] == static_cast<int>(i) &&
                f.detections[d].class_name == scene.objects[i].model->name;
      }
    }
    n += seen >= min_frames;
  }
  return n;
}

}  // namespace geofusion
