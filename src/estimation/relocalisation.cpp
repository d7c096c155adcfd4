#include "geofusion/estimation/relocalisation.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace geofusion {
namespace {

constexpr int kMaxHypotheses = 20000;

// A rotation taking `up` to +z: corrections are a heading about z and a translation there.
Eigen::Matrix3d gravityFrame(const Eigen::Vector3d& gravity) {
  const Eigen::Vector3d up = -gravity.normalized();
  return Eigen::Quaterniond::FromTwoVectors(up, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

// The heading-and-translation transform (in the map frame) that best takes points `a` onto `b`
// (least squares), given the gravity frame R_g.
Eigen::Isometry3d headingAndTranslation(const std::vector<Eigen::Vector3d>& a,
                                        const std::vector<Eigen::Vector3d>& b,
                                        const Eigen::Matrix3d& R_g) {
  Eigen::Vector3d mean_a = Eigen::Vector3d::Zero(), mean_b = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < a.size(); ++i) mean_a += R_g * a[i], mean_b += R_g * b[i];
  mean_a /= static_cast<double>(a.size());
  mean_b /= static_cast<double>(b.size());
  double sin_sum = 0.0, cos_sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Eigen::Vector3d p = R_g * a[i] - mean_a, q = R_g * b[i] - mean_b;
    sin_sum += p.x() * q.y() - p.y() * q.x();
    cos_sum += p.x() * q.x() + p.y() * q.y();
  }
  Eigen::Isometry3d T_g = Eigen::Isometry3d::Identity();
  T_g.linear() = Eigen::AngleAxisd(std::atan2(sin_sum, cos_sum), Eigen::Vector3d::UnitZ()).matrix();
  T_g.translation() = mean_b - T_g.linear() * mean_a;
  Eigen::Isometry3d R = Eigen::Isometry3d::Identity();
  R.linear() = R_g;
  return R.inverse() * T_g * R;
}

// The correction moves the detections (about `centre`) by at most the configured bounds; the
// translation is measured there, not at the map's origin (a heading correction far from the
// origin has a large translation part).
bool withinBounds(const Eigen::Isometry3d& T, const Eigen::Vector3d& centre,
                  const RelocalisationConfig& config) {
  return (T * centre - centre).norm() <= config.max_translation_m &&
         Eigen::AngleAxisd(T.linear()).angle() <= config.max_rotation_deg * M_PI / 180.0;
}

// The object of `d`'s class nearest to T d within `inlier_m`, or -1.
int nearestObject(const LabelledPoint& d, const std::vector<LabelledPoint>& objects,
                  const Eigen::Isometry3d& T, double inlier_m) {
  const Eigen::Vector3d p = T * d.position;
  int best = -1;
  double best_d = inlier_m;
  for (std::size_t j = 0; j < objects.size(); ++j) {
    if (objects[j].class_name != d.class_name) continue;
    const double dist = (objects[j].position - p).norm();
    if (dist <= best_d) best_d = dist, best = static_cast<int>(j);
  }
  return best;
}

// Detections on objects of their class (within `inlier_m`) after moving them by `T`.
int detectionsOnMap(const std::vector<LabelledPoint>& detections,
                    const std::vector<LabelledPoint>& objects, const Eigen::Isometry3d& T,
                    double inlier_m) {
  int n = 0;
  for (const LabelledPoint& d : detections) n += nearestObject(d, objects, T, inlier_m) >= 0;
  return n;
}

}  // namespace

Relocalisation relocalise(const std::vector<LabelledPoint>& detections,
                          const std::vector<LabelledPoint>& objects, const Eigen::Vector3d& gravity,
                          const RelocalisationConfig& config) {
  Relocalisation out;
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  out.inliers_before = out.inliers_after =
      detectionsOnMap(detections, objects, identity, config.inlier_m);
  if (!config.enabled || static_cast<int>(detections.size()) < config.min_inliers ||
      out.inliers_before >= config.max_share_on_map * static_cast<double>(detections.size()))
    return out;
  out.tried = true;
  const Eigen::Matrix3d R_g = gravityFrame(gravity);
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const LabelledPoint& d : detections) centre += d.position;
  centre /= static_cast<double>(detections.size());
  // Hypotheses from two correspondences of the same classes whose spacing agrees.
  Eigen::Isometry3d best = identity;
  int best_inliers = out.inliers_before, hypotheses = 0;
  const std::size_t n = detections.size();
  for (std::size_t i = 0; i < n && hypotheses < kMaxHypotheses; ++i) {
    for (std::size_t k = i + 1; k < n && hypotheses < kMaxHypotheses; ++k) {
      const double spacing = (detections[i].position - detections[k].position).norm();
      if (spacing < 2.0 * config.inlier_m) continue;  // too close to fix a heading
      for (std::size_t a = 0; a < objects.size(); ++a) {
        if (objects[a].class_name != detections[i].class_name) continue;
        for (std::size_t b = 0; b < objects.size(); ++b) {
          if (b == a || objects[b].class_name != detections[k].class_name) continue;
          if (std::abs((objects[a].position - objects[b].position).norm() - spacing) >
              2.0 * config.inlier_m)
            continue;
          ++hypotheses;
          const Eigen::Isometry3d T =
              headingAndTranslation({detections[i].position, detections[k].position},
                                    {objects[a].position, objects[b].position}, R_g);
          if (!withinBounds(T, centre, config)) continue;
          const int inliers = detectionsOnMap(detections, objects, T, config.inlier_m);
          if (inliers > best_inliers) best_inliers = inliers, best = T;
        }
      }
    }
  }
  if (best_inliers <= out.inliers_before) return out;
  // Refined on every detection it brings onto an object.
  std::vector<Eigen::Vector3d> from, to;
  for (const LabelledPoint& d : detections) {
    const int j = nearestObject(d, objects, best, config.inlier_m);
    if (j < 0) continue;
    from.push_back(d.position);
    to.push_back(objects[static_cast<std::size_t>(j)].position);
  }
  const Eigen::Isometry3d refined = headingAndTranslation(from, to, R_g);
  const int refined_inliers = detectionsOnMap(detections, objects, refined, config.inlier_m);
  if (refined_inliers >= best_inliers && withinBounds(refined, centre, config))
    best = refined, best_inliers = refined_inliers;
  if (best_inliers < config.min_inliers ||
      best_inliers < config.min_gain * out.inliers_before + 1.0)
    return out;
  out.applied = true;
  out.inliers_after = best_inliers;
  out.T_correction = best;
  return out;
}

}  // namespace geofusion
