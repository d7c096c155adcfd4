#include "geofusion/estimation/relocalisation.h"

#include "geofusion/common/enum_names.h"

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

// Squared Mahalanobis distance of correction T (its translation at `centre`, its rotation)
// against the odometry's drift; 0 when the drift is unknown.
double mahalanobisSq(const Eigen::Isometry3d& T, const Eigen::Vector3d& centre,
                     const OdometryDrift& drift) {
  if (!std::isfinite(drift.sigma_m) || !std::isfinite(drift.sigma_rad)) return 0.0;
  const double t = (T * centre - centre).norm() / std::max(drift.sigma_m, 1e-9);
  const double r = Eigen::AngleAxisd(T.linear()).angle() / std::max(drift.sigma_rad, 1e-12);
  return t * t + r * r;
}

// The object each detection lands on under correction T (-1: none).
std::vector<int> matchesOf(const Eigen::Isometry3d& T, const std::vector<LabelledPoint>& detections,
                           const std::vector<LabelledPoint>& objects, double inlier_m) {
  std::vector<int> out;
  for (const LabelledPoint& d : detections) out.push_back(nearestObject(d, objects, T, inlier_m));
  return out;
}

// Another explanation of the detections than `best`: fewer than half of the detections it puts
// on objects go to the objects `best` puts them on (a turn about a near-symmetric layout, the
// other of two repeated groups; not a slightly different fit of the same matches).
bool alternative(const std::vector<int>& matches, const std::vector<int>& best) {
  int matched = 0, agreeing = 0;
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if (matches[i] < 0) continue;
    ++matched;
    agreeing += matches[i] == best[i];
  }
  return matched > 0 && 2 * agreeing < matched;
}

struct Hypothesis {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  int inliers = 0;
  double mahalanobis_sq = 0.0;
};

// Hypotheses from two correspondences of the same classes whose spacing agrees, within the
// configured bounds, with their support and their distance against the drift. The first one is
// no correction.
std::vector<Hypothesis> pairHypotheses(const std::vector<LabelledPoint>& detections,
                                       const std::vector<LabelledPoint>& objects,
                                       const Eigen::Matrix3d& R_g, const Eigen::Vector3d& centre,
                                       const RelocalisationConfig& config,
                                       const OdometryDrift& drift) {
  std::vector<Hypothesis> out(1);
  out[0].inliers = detectionsOnMap(detections, objects, out[0].T, config.inlier_m);
  int tried = 0;
  const std::size_t n = detections.size();
  for (std::size_t i = 0; i < n && tried < kMaxHypotheses; ++i) {
    for (std::size_t k = i + 1; k < n && tried < kMaxHypotheses; ++k) {
      const double spacing = (detections[i].position - detections[k].position).norm();
      if (spacing < 2.0 * config.inlier_m) continue;  // too close to fix a heading
      for (std::size_t a = 0; a < objects.size(); ++a) {
        if (objects[a].class_name != detections[i].class_name) continue;
        for (std::size_t b = 0; b < objects.size(); ++b) {
          if (b == a || objects[b].class_name != detections[k].class_name) continue;
          if (std::abs((objects[a].position - objects[b].position).norm() - spacing) >
              2.0 * config.inlier_m)
            continue;
          ++tried;
          Hypothesis h;
          h.T = headingAndTranslation({detections[i].position, detections[k].position},
                                      {objects[a].position, objects[b].position}, R_g);
          if (!withinBounds(h.T, centre, config)) continue;
          h.inliers = detectionsOnMap(detections, objects, h.T, config.inlier_m);
          h.mahalanobis_sq = mahalanobisSq(h.T, centre, drift);
          out.push_back(h);
        }
      }
    }
  }
  return out;
}

// The best hypothesis refined on every detection it brings onto an object, when that keeps its
// support, its bounds and its gate.
Hypothesis refined(const Hypothesis& best, const std::vector<LabelledPoint>& detections,
                   const std::vector<LabelledPoint>& objects, const Eigen::Matrix3d& R_g,
                   const Eigen::Vector3d& centre, const RelocalisationConfig& config,
                   const OdometryDrift& drift) {
  std::vector<Eigen::Vector3d> from, to;
  for (const LabelledPoint& d : detections) {
    const int j = nearestObject(d, objects, best.T, config.inlier_m);
    if (j < 0) continue;
    from.push_back(d.position);
    to.push_back(objects[static_cast<std::size_t>(j)].position);
  }
  if (from.size() < 2) return best;
  Hypothesis h;
  h.T = headingAndTranslation(from, to, R_g);
  h.inliers = detectionsOnMap(detections, objects, h.T, config.inlier_m);
  h.mahalanobis_sq = mahalanobisSq(h.T, centre, drift);
  const bool keeps = h.inliers >= best.inliers && withinBounds(h.T, centre, config) &&
                     h.mahalanobis_sq <= std::max(config.gate_chi2, best.mahalanobis_sq);
  return keeps ? h : best;
}

const std::pair<RelocalisationDecision, const char*> kDecisionNames[] = {
    {RelocalisationDecision::kNotSearched, "not_searched"},
    {RelocalisationDecision::kApplied, "applied"},
    {RelocalisationDecision::kNoGain, "no_gain"},
    {RelocalisationDecision::kBeyondDrift, "beyond_drift"},
    {RelocalisationDecision::kAmbiguous, "ambiguous"},
};

}  // namespace

const char* toString(RelocalisationDecision decision) {
  return nameIn(kDecisionNames, decision);
}

bool parseRelocalisationDecision(const std::string& name, RelocalisationDecision* decision) {
  return parseIn(kDecisionNames, name, decision);
}

Eigen::Vector3d centreOf(const std::vector<LabelledPoint>& points) {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const LabelledPoint& p : points) centre += p.position;
  return points.empty() ? centre : Eigen::Vector3d(centre / static_cast<double>(points.size()));
}

OdometryDrift accumulatedDrift(const std::vector<Eigen::Isometry3d>& path,
                               const Eigen::Vector3d& centre, const RelocalisationConfig& config,
                               double sigma_position_m, double sigma_rotation_rad) {
  OdometryDrift out;
  double turned = 0.0, lever = 0.0;
  for (std::size_t i = 0; i < path.size(); ++i) {
    lever = std::max(lever, (centre - path[i].translation()).norm());
    if (i == 0) continue;
    const Eigen::Isometry3d step = path[i - 1].inverse() * path[i];
    out.path_m += step.translation().norm();
    turned += Eigen::AngleAxisd(step.linear()).angle();
    ++out.keyframes;
  }
  const double n = out.keyframes;
  const double systematic_rad =
      config.drift_rad_per_m * out.path_m + config.drift_rad_per_rad * turned;
  out.sigma_rad =
      std::sqrt(n * sigma_rotation_rad * sigma_rotation_rad + systematic_rad * systematic_rad);
  const double systematic_m = config.drift_fraction * out.path_m;
  out.sigma_m = std::sqrt(n * sigma_position_m * sigma_position_m + systematic_m * systematic_m +
                          out.sigma_rad * out.sigma_rad * lever * lever);
  return out;
}

Relocalisation relocalise(const std::vector<LabelledPoint>& detections,
                          const std::vector<LabelledPoint>& objects, const Eigen::Vector3d& gravity,
                          const RelocalisationConfig& config, const OdometryDrift& drift) {
  Relocalisation out;
  out.drift = drift;
  out.detections = static_cast<int>(detections.size());
  out.inliers_before = out.inliers_after =
      detectionsOnMap(detections, objects, Eigen::Isometry3d::Identity(), config.inlier_m);
  const bool on_map =
      out.inliers_before >= config.max_share_on_map * static_cast<double>(detections.size());
  out.agreed = out.inliers_before > 0 && on_map;
  if (!config.enabled || out.detections < config.min_inliers || on_map) return out;
  out.tried = true;
  out.decision = RelocalisationDecision::kNoGain;
  const Eigen::Matrix3d R_g = gravityFrame(gravity);
  const Eigen::Vector3d centre = centreOf(detections);
  const std::vector<Hypothesis> hypotheses =
      pairHypotheses(detections, objects, R_g, centre, config, drift);
  // The best within the odometry's reach, and the best of all (to say why one is refused).
  std::size_t best = 0, best_any = 0;
  for (std::size_t h = 1; h < hypotheses.size(); ++h) {
    if (hypotheses[h].inliers > hypotheses[best_any].inliers) best_any = h;
    if (hypotheses[h].mahalanobis_sq <= config.gate_chi2 &&
        hypotheses[h].inliers > hypotheses[best].inliers)
      best = h;
  }
  auto gains = [&](const Hypothesis& h) {
    return h.inliers > out.inliers_before && h.inliers >= config.min_inliers &&
           h.inliers >= config.min_gain * out.inliers_before + 1.0;
  };
  if (!gains(hypotheses[best])) {
    if (gains(hypotheses[best_any])) {
      out.decision = RelocalisationDecision::kBeyondDrift;
      out.inliers_after = hypotheses[best_any].inliers;
      out.mahalanobis_sq = hypotheses[best_any].mahalanobis_sq;
      out.T_correction = hypotheses[best_any].T;
    }
    return out;
  }
  const Hypothesis chosen =
      refined(hypotheses[best], detections, objects, R_g, centre, config, drift);
  out.inliers_after = chosen.inliers;
  out.mahalanobis_sq = chosen.mahalanobis_sq;
  out.T_correction = chosen.T;
  // The runner-up: the best other explanation the odometry allows (no correction included).
  const std::vector<int> chosen_matches = matchesOf(chosen.T, detections, objects, config.inlier_m);
  for (const Hypothesis& h : hypotheses) {
    if (h.mahalanobis_sq <= config.gate_chi2 && h.inliers > out.runner_up &&
        alternative(matchesOf(h.T, detections, objects, config.inlier_m), chosen_matches))
      out.runner_up = h.inliers;
  }
  if (chosen.inliers - out.runner_up < config.min_margin) {
    out.decision = RelocalisationDecision::kAmbiguous;
    return out;
  }
  out.decision = RelocalisationDecision::kApplied;
  out.applied = true;
  return out;
}

}  // namespace geofusion
