#include "geofusion/estimation/scene_estimator.h"

#include "geofusion/estimation/refinement_pool.h"
#include "geofusion/estimation/separation.h"

#include "geofusion/common/enum_names.h"
#include "geofusion/common/statistics.h"
#include "geofusion/model/collision.h"
#include "geofusion/render/consistency.h"
#include "geofusion/render/renderer.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <set>

namespace geofusion {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace

const char* toString(Method method) {
  switch (method) {
    case Method::kFrameByFrame: return "FbF";
    case Method::kFrameByFrameRefined: return "FbF-R";
    case Method::kBaselineSlam: return "B-SLAM";
    case Method::kRobustFrontEnd: return "R-Front";
    default: return "GeoFusion";
  }
}

bool parseMethod(const std::string& name, Method* method) {
  std::string n;
  for (char c : name)
    if (c != '-' && c != '_') n += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (n == "fbf" || n == "framebyframe")
    *method = Method::kFrameByFrame;
  else if (n == "fbfr" || n == "fbfrefined")
    *method = Method::kFrameByFrameRefined;
  else if (n == "bslam")
    *method = Method::kBaselineSlam;
  else if (n == "rfront")
    *method = Method::kRobustFrontEnd;
  else if (n == "geofusion")
    *method = Method::kGeoFusion;
  else
    return false;
  return true;
}

MethodStages stagesOf(Method method) {
  MethodStages s;
  switch (method) {
    case Method::kFrameByFrame: s.map_is_keyframe_detections = true; break;
    case Method::kFrameByFrameRefined:
      s.map_is_keyframe_detections = s.depth_refinement = true;
      break;
    case Method::kBaselineSlam: s.stage_one = true; break;
    case Method::kRobustFrontEnd: s.geometric_consistency = s.false_positive_removal = true; break;
    case Method::kGeoFusion:
      s.geometric_consistency = s.false_positive_removal = true;
      s.stage_one = s.relations_and_stage_two = s.depth_refinement = true;
      s.stage_one_noise_adaptation = s.free_space_removal = s.relocalisation = true;
      s.class_by_consistency = true;
      break;
  }
  return s;
}

namespace {
const std::pair<DetectionDecision, const char*> kDecisionNames[] = {
    {DetectionDecision::kSkipped, "skipped"},
    {DetectionDecision::kFrameObject, "frame_object"},
    {DetectionDecision::kNewObject, "new_object"},
    {DetectionDecision::kNewCandidate, "new_candidate"},
    {DetectionDecision::kAssociated, "associated"},
    {DetectionDecision::kCandidate, "candidate"},
    {DetectionDecision::kRemoved, "removed"},
    {DetectionDecision::kClassKept, "class_kept"},
    {DetectionDecision::kClassChanged, "class_changed"},
};
// The refinement a method runs: the configured one, on only when its stages include it.
DepthRefinementConfig refinementOf(const EstimatorConfig& config, const MethodStages& stages) {
  DepthRefinementConfig r = config.refinement;
  r.enabled = r.enabled && stages.depth_refinement;
  return r;
}
}  // namespace

const char* toString(DetectionDecision decision) {
  return nameIn(kDecisionNames, decision);
}

bool parseDetectionDecision(const std::string& name, DetectionDecision* decision) {
  return parseIn(kDecisionNames, name, decision);
}

SceneEstimator::SceneEstimator(const ModelSet& models, const EstimatorConfig& config,
                               std::shared_ptr<OffscreenRenderer> renderer)
    : config_(config), stages_(stagesOf(config.method)), monitor_(config.monitor) {
  for (const auto& m : models.models()) models_[m->name] = m;
  if (!renderer) renderer = std::make_shared<OffscreenRenderer>();
  scorer_ = std::make_unique<ConsistencyScorer>(std::move(renderer), config.consistency);
  refiner_ = std::make_unique<DepthRefiner>(scorer_.get(), refinementOf(config, stages_));
  collider_ = std::make_unique<HullCollider>();
  if (stages_.geometric_consistency || stages_.depth_refinement) {
    std::vector<std::shared_ptr<const ObjectModel>> all;
    for (const auto& [name, model] : models_) all.push_back(model);
    pool_ =
        std::make_unique<RefinementPool>(std::max(0, config.consistency.threads - 1),
                                         config.consistency, refinementOf(config, stages_), all);
  }
}

SceneEstimator::~SceneEstimator() = default;

void SceneEstimator::prepare() {
  for (const auto& [name, model] : models_) {
    scorer_->prepare(model);
    collider_->prepare(model);
  }
}

void SceneEstimator::setConfig(const EstimatorConfig& config) {
  const Method method = config_.method;
  config_ = config;
  config_.method = method;
  scorer_->setConfig(config.consistency);
  refiner_->setConfig(refinementOf(config_, stages_));
  if (pool_) pool_->setConfig(config.consistency, refinementOf(config_, stages_));
  monitor_.setConfig(config.monitor);
}

bool SceneEstimator::resume(const std::vector<ObjectEstimate>& objects,
                            const Eigen::Isometry3d& T_map_odom, int next_object_id,
                            const SupportPlane* support) {
  if (!T_map_cam_.empty()) return false;
  if (support && support->valid && support->inliers > 0 && support->size.minCoeff() > 0.0) {
    support_ = *support;
    support_model_ =
        supportPlaneModel(support_, &T_map_support_, config_.support_plane.thickness_m);
  }
  tracks_.clear();
  next_id_ = std::max(next_id_, next_object_id);
  for (const ObjectEstimate& o : objects) {
    if (!o.model || !o.T_map_obj.matrix().allFinite()) continue;
    Track& tr = startTrack(o.model, o.T_map_obj, -1);
    tr.id = o.id;
    tr.confirmed = true;
    tr.best_consistency = o.best_consistency;
    tr.prior_measurements = std::max(0, o.measurements);
    tr.prior_evidence = tr.prior_measurements * std::max(0.0, o.best_consistency);
    // The history's rotations as the symmetric equivalent nearest the saved pose.
    tr.prior.add(o.history, tr.symmetryModel(), o.T_map_obj.linear());
    tr.folded = tr.prior;
    next_id_ = std::max(next_id_, o.id + 1);
  }
  T_map_odom_start_ = T_map_odom;
  relocalisation_anchor_ = -1;  // where the robot is against the map is not known yet
  return true;
}

void SceneEstimator::reset() {
  T_map_odom_start_ = Eigen::Isometry3d::Identity();
  relocalisation_anchor_ = 0;
  T_odom_fix_ = Eigen::Isometry3d::Identity();
  tracks_.clear();
  T_map_cam_.clear();
  T_odom_cam_.clear();
  odometry_variance_ = 1.0;
  stamps_.clear();
  support_ = SupportPlane();
  support_model_.reset();
  contacts_.clear();
  contacts_by_id_.clear();
  held_contacts_.clear();
  separations_by_id_.clear();
  frame_objects_.clear();
  monitor_.reset();
}

Eigen::Isometry3d SceneEstimator::T_map_odom() const {
  if (T_map_cam_.empty()) return Eigen::Isometry3d::Identity();
  // The odometry kept is T_odom_fix_ x the robot's: map -> the robot's odom frame.
  return T_map_cam_.back() * T_odom_cam_.back().inverse() * T_odom_fix_;
}

const Eigen::Isometry3d& SceneEstimator::reportedPose(const Track& track) const {
  return stages_.relations_and_stage_two ? track.T_refined : track.T_stage_one;
}

ObjectEstimate SceneEstimator::estimateOf(const Track& track) const {
  ObjectEstimate e;
  e.id = track.id;
  e.model = track.model;
  e.T_map_obj = reportedPose(track);
  e.measurements = track.measurementCount();
  e.best_consistency = track.best_consistency;
  e.false_positive = falsePositiveScore(track.best_consistency, e.measurements);
  e.existence = 1.0 - e.false_positive;
  e.first_keyframe = track.first_keyframe;
  e.last_keyframe = track.last_keyframe;
  e.confirmed = track.confirmed || !stages_.false_positive_removal;
  e.covariance = poseSpread(track, e.T_map_obj);
  return e;
}

Eigen::Matrix<double, 6, 6> SceneEstimator::poseSpread(const Track& track,
                                                       const Eigen::Isometry3d& T_map_obj) const {
  // The spread is taken over the latest measurements only (bounded work a keyframe on long runs)
  // and divided by the number of all of them.
  constexpr std::size_t kSpreadMeasurements = 100;
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  const Symmetry& symmetry = track.symmetryModel()->symmetry;
  const std::size_t n_all = track.observations.size();
  int n = 0;
  for (std::size_t k = n_all - std::min(n_all, kSpreadMeasurements); k < n_all; ++k) {
    const Observation& o = track.observations[k];
    if (o.keyframe < 0 || o.keyframe >= static_cast<int>(T_map_cam_.size())) continue;
    const Eigen::Isometry3d T = T_map_cam_[static_cast<std::size_t>(o.keyframe)] * o.T_cam_obj;
    const Eigen::Matrix3d R = closestSymmetricEquivalent(symmetry, T_map_obj.linear(), T.linear());
    Eigen::Matrix<double, 6, 1> d;
    d.head<3>() = T.translation() - T_map_obj.translation();
    const Eigen::AngleAxisd error(T_map_obj.linear().transpose() * R);
    Eigen::Vector3d rotation = error.angle() * error.axis();  // object frame
    if (symmetry.type == Symmetry::Type::kContinuous)
      rotation -= rotation.dot(symmetry.axis) * symmetry.axis;
    d.tail<3>() = T_map_obj.linear() * rotation;
    covariance += d * d.transpose();
    ++n;
  }
  if (n < 2) return Eigen::Matrix<double, 6, 6>::Zero();
  return covariance / ((n - 1) * static_cast<double>(std::max<std::size_t>(n, n_all)));
}

std::vector<ObjectEstimate> SceneEstimator::objects() const {
  if (stages_.map_is_keyframe_detections) return frame_objects_;
  std::vector<ObjectEstimate> out;
  for (std::size_t j : reportedTracks()) out.push_back(estimateOf(tracks_[j]));
  return out;
}

KeyframeResult SceneEstimator::result(int keyframe, double stamp) const {
  KeyframeResult r;
  r.keyframe = keyframe;
  r.stamp_s = stamp;
  if (!T_map_cam_.empty()) r.T_map_cam = T_map_cam_.back();
  r.objects = objects();
  if (stages_.false_positive_removal && !stages_.map_is_keyframe_detections) {
    for (const Track& track : tracks_)
      if (!track.confirmed) r.tentative.push_back(estimateOf(track));
  }
  if (stages_.relations_and_stage_two) r.contacts = onePerPairAndType(contacts_);
  return r;
}

std::vector<int> SceneEstimator::sightedTracks(const ScoredDetections& detections,
                                               const std::vector<int>& measured) const {
  std::vector<int> sighted = measured;
  const double reach = config_.lifecycle.detected_nearby_m;
  if (reach <= 0.0 || T_map_cam_.empty()) return sighted;
  for (const Track& tr : tracks_) {
    if (!tr.confirmed || std::find(sighted.begin(), sighted.end(), tr.id) != sighted.end())
      continue;
    const Eigen::Vector3d centre = reportedPose(tr) * tr.box_centre;
    for (int k : detections.usable) {
      const std::size_t i = static_cast<std::size_t>(k);
      if (!detections.models[i] || detections.models[i]->name != tr.model->name) continue;
      const Eigen::Vector3d seen = T_map_cam_.back() * detections.pose(i) * tr.box_centre;
      if ((seen - centre).norm() <= reach) {
        sighted.push_back(tr.id);
        break;
      }
    }
  }
  return sighted;
}

KeyframeResult SceneEstimator::addKeyframe(const Keyframe& kf) {
  const auto start = Clock::now();
  StageTimings timings;
  const int t = static_cast<int>(T_map_cam_.size());
  appendCameraPose(kf);

  auto t0 = Clock::now();
  const ScoredDetections detections = scoreDetections(kf);
  timings.consistency_ms = msSince(t0);

  t0 = Clock::now();
  Relocalisation relocalisation;
  if (stages_.relocalisation) relocalisation = relocaliseCamera(detections);
  std::vector<int> started, contests(kf.detections.size(), 0);
  std::vector<int> detection_object =
      stages_.map_is_keyframe_detections
          ? mapKeyframeDetections(kf, detections, t)
          : associateDetections(kf, detections, t, &started, &contests);
  const std::vector<int> assigned = detection_object;
  timings.association_ms = msSince(t0);

  t0 = Clock::now();
  std::vector<Removal> removals;
  std::vector<int> removed;
  if (stages_.false_positive_removal) {
    std::vector<int> touched;
    for (int id : detection_object)
      if (id >= 0) touched.push_back(id);
    confirmOrTimeOut(&tracks_, touched, t, config_.association, &removals);
    if (stages_.free_space_removal && kf.depth.data) {
      const Eigen::Isometry3d T_cam_map = T_map_cam_.back().inverse();
      removeSeenAbsent(
          &tracks_, sightedTracks(detections, touched), t, config_.lifecycle,
          [&](const Track& tr) {
            return scorer_->score(tr.model, T_cam_map * reportedPose(tr), kf.depth, kf.K);
          },
          &removals);
    }
    mergeOverlapping(
        &tracks_, config_.association, collider_.get(),
        [this](const Track& tr) -> const Eigen::Isometry3d& { return reportedPose(tr); },
        [this](const Track& tr) { return recentlySeen(tr); }, &removals);
    for (const Removal& r : removals) removed.push_back(r.id);
    for (int& id : detection_object) {
      if (std::find(removed.begin(), removed.end(), id) != removed.end()) id = -1;
    }
  }
  timings.lifecycle_ms = msSince(t0);

  StageReport stage_one, stage_two;
  if (stages_.stage_one && stageOneDue(t)) {
    t0 = Clock::now();
    stage_one = runStageOne();
    timings.stage_one_ms = msSince(t0);
  }
  if (stages_.relations_and_stage_two) stage_two = runRelationsAndStageTwo(&kf, &timings);

  KeyframeResult out = result(t, kf.stamp_s);
  out.detections = reportDetections(kf, detections, assigned, started, removed, contests);
  out.detection_warning = monitor_.add(out.detections);
  out.removed_ids = std::move(removed);
  out.removals = std::move(removals);
  out.skipped_detections = detections.skipped;
  out.relocalisation = relocalisation;
  out.stage_one = stage_one;
  out.stage_two = stage_two;
  timings.total_ms = msSince(start);
  out.timings = timings;
  return out;
}

// The camera pose of a new keyframe: chained from the previous estimate by the odometry increment.
Eigen::Isometry3d SceneEstimator::appendCameraPose(const Keyframe& kf) {
  const Eigen::Isometry3d T_map_cam =
      T_map_cam_.empty()
          ? T_map_odom_start_ * kf.T_odom_cam
          : T_map_cam_.back() * (T_odom_cam_.back().inverse() * T_odom_fix_ * kf.T_odom_cam);
  T_map_cam_.push_back(T_map_cam);
  T_odom_cam_.push_back(T_odom_fix_ * kf.T_odom_cam);
  stamps_.push_back(kf.stamp_s);
  return T_map_cam;
}

// Relocalisation (relocalisation.h): the keyframe's detections against the map's objects; a
// correction moves this keyframe's camera, so that its detections associate with the objects
// they see, and replaces the odometry increment into it (the drive that drifted) by the
// corrected one: the odometry kept from here on is T_odom_fix_ x the robot's.
Relocalisation SceneEstimator::relocaliseCamera(const ScoredDetections& detections) {
  std::vector<LabelledPoint> seen, mapped;
  const std::size_t t = T_map_cam_.size() - 1;
  const Eigen::Isometry3d& T_map_cam = T_map_cam_.back();
  for (int k : detections.usable) {
    const std::size_t i = static_cast<std::size_t>(k);
    seen.push_back({detections.models[i]->name, (T_map_cam * detections.pose(i)).translation()});
  }
  for (std::size_t j : reportedTracks())
    mapped.push_back({tracks_[j].model->name, reportedPose(tracks_[j]).translation()});
  if (mapped.empty()) {  // nothing to drift against: the camera makes the map
    if (relocalisation_anchor_ >= 0) relocalisation_anchor_ = static_cast<int>(t);
    return Relocalisation();
  }
  const Relocalisation r =
      relocalise(seen, mapped, config_.gravity, config_.relocalisation, driftSinceAnchor(seen));
  if (r.agreed || r.applied) relocalisation_anchor_ = static_cast<int>(t);
  if (!r.applied) return r;
  if (t == 0) {  // a resumed map: the first camera is placed through it
    T_map_cam_[0] = r.T_correction * T_map_cam_[0];
    return r;
  }
  const Eigen::Isometry3d robot_odom = T_odom_fix_.inverse() * T_odom_cam_[t];
  T_map_cam_[t] = r.T_correction * T_map_cam_[t];
  T_odom_cam_[t] = T_odom_cam_[t - 1] * (T_map_cam_[t - 1].inverse() * T_map_cam_[t]);
  T_odom_fix_ = T_odom_cam_[t] * robot_odom.inverse();
  return r;
}

// How far the odometry can have taken the camera from the map since the last keyframe whose
// detections agreed with it (relocalisation.h); unknown (no gate) on a resumed map until then.
OdometryDrift SceneEstimator::driftSinceAnchor(const std::vector<LabelledPoint>& seen) const {
  if (relocalisation_anchor_ < 0 || seen.empty()) return OdometryDrift();
  const Eigen::Vector3d centre = centreOf(seen);
  const std::size_t anchor =
      std::min(static_cast<std::size_t>(relocalisation_anchor_), T_odom_cam_.size() - 1);
  const std::vector<Eigen::Isometry3d> path(
      T_odom_cam_.begin() + static_cast<std::ptrdiff_t>(anchor), T_odom_cam_.end());
  // The path in the odometry frame, the centre brought there through the current camera.
  const Eigen::Vector3d centre_odom = T_odom_cam_.back() * (T_map_cam_.back().inverse() * centre);
  return accumulatedDrift(path, centre_odom, config_.relocalisation,
                          config_.stage_one.odometry_sigma_position_m,
                          config_.stage_one.odometry_sigma_rotation_rad);
}

// Usable detections (known class, enough score, finite pose), depth-refined when the method
// refines, and their scores: the geometric consistency f_gc at the pose used, or the detector's
// own score for methods without it.
SceneEstimator::ScoredDetections SceneEstimator::scoreDetections(const Keyframe& kf) const {
  ScoredDetections out;
  out.models.resize(kf.detections.size());
  out.score.assign(kf.detections.size(), -1.0);
  out.refinement.resize(kf.detections.size());
  const bool render = stages_.geometric_consistency || stages_.depth_refinement;
  for (std::size_t k = 0; k < kf.detections.size(); ++k) {
    const ObjectMeasurement& d = kf.detections[k];
    out.refinement[k].T_cam_obj = d.T_cam_obj;
    const auto it = models_.find(d.class_name);
    if (it == models_.end() || d.score < config_.min_detection_score ||
        !d.T_cam_obj.matrix().allFinite()) {
      ++out.skipped;
      continue;
    }
    out.models[k] = it->second;
    out.usable.push_back(static_cast<int>(k));
  }
  // Each usable detection refined and scored against the depth (in the pool's threads too).
  if (render) {
    std::vector<RefinementJob> jobs;
    for (int k : out.usable) jobs.push_back({out.models[k], kf.detections[k].T_cam_obj});
    const std::vector<DepthRefinement> refined =
        pool_->refine(jobs, kf.depth, kf.K, refiner_.get());  // 1 thread: all in this one
    for (std::size_t i = 0; i < jobs.size(); ++i)
      out.refinement[static_cast<std::size_t>(out.usable[i])] = refined[i];
  }
  for (int k : out.usable) {
    if (!stages_.geometric_consistency) {
      out.score[k] = kf.detections[k].score;
    } else if (kf.depth.data) {
      out.score[k] = out.refinement[k].after.score;
    } else {
      out.score[k] = config_.consistency.undetermined_score;
    }
  }
  return out;
}

// Each detection's report: its poses, refinement, score and what became of it.
std::vector<DetectionReport> SceneEstimator::reportDetections(
    const Keyframe& kf, const ScoredDetections& detections,
    const std::vector<int>& detection_object, const std::vector<int>& started,
    const std::vector<int>& removed, const std::vector<int>& contests) const {
  auto contains = [](const std::vector<int>& v, int x) {
    return std::find(v.begin(), v.end(), x) != v.end();
  };
  std::vector<DetectionReport> out(kf.detections.size());
  for (std::size_t k = 0; k < kf.detections.size(); ++k) {
    const ObjectMeasurement& d = kf.detections[k];
    const DepthRefinement& r = detections.refinement[k];
    DetectionReport& rep = out[k];
    rep.class_name = d.class_name;
    rep.detector_score = d.score;
    rep.T_cam_in = d.T_cam_obj;
    rep.T_cam_out = r.T_cam_obj;
    rep.refinement = r.outcome;
    rep.ray_offset_m = r.ray_offset_m;
    rep.correction_translation_m = r.correction_translation_m;
    rep.correction_rotation_rad = r.correction_rotation_rad;
    rep.consistency = detections.score[k];
    rep.r_in = r.after.r_in, rep.r_out = r.after.r_out, rep.r_occ = r.after.r_occ;
    rep.object = detection_object[k];
    if (!detections.models[k] || rep.object < 0) continue;  // skipped
    if (stages_.map_is_keyframe_detections) {
      rep.decision = DetectionDecision::kFrameObject;
      continue;
    }
    const auto track = std::find_if(tracks_.begin(), tracks_.end(),
                                    [&](const Track& tr) { return tr.id == rep.object; });
    const bool in_map =
        track != tracks_.end() && (track->confirmed || !stages_.false_positive_removal);
    if (contains(removed, rep.object) || track == tracks_.end())
      rep.decision = DetectionDecision::kRemoved;
    else if (contests[k] > 0)
      rep.decision =
          contests[k] == 2 ? DetectionDecision::kClassChanged : DetectionDecision::kClassKept;
    else if (contains(started, rep.object))
      rep.decision = in_map ? DetectionDecision::kNewObject : DetectionDecision::kNewCandidate;
    else
      rep.decision = in_map ? DetectionDecision::kAssociated : DetectionDecision::kCandidate;
  }
  return out;
}

// FbF: the keyframe's usable detections, each an object of its own. Returns each detection's
// object id (-1: none).
std::vector<int> SceneEstimator::mapKeyframeDetections(const Keyframe& kf,
                                                       const ScoredDetections& detections, int t) {
  std::vector<int> detection_object(kf.detections.size(), -1);
  frame_objects_.clear();
  for (int k : detections.usable) {
    const ObjectMeasurement& d = kf.detections[static_cast<std::size_t>(k)];
    ObjectEstimate e;
    e.id = next_id_++;
    e.model = detections.models[static_cast<std::size_t>(k)];
    e.T_map_obj = T_map_cam_.back() * detections.pose(static_cast<std::size_t>(k));
    e.existence = d.score;
    e.false_positive = 1.0 - d.score;
    e.best_consistency = d.score;
    e.measurements = 1;
    e.first_keyframe = e.last_keyframe = t;
    detection_object[static_cast<std::size_t>(k)] = e.id;
    frame_objects_.push_back(e);
  }
  return detection_object;
}

// Algorithm 1: each usable detection goes to the object of highest likelihood (one measurement
// per object), or starts a new object. Returns each detection's object id (-1: none).
std::vector<int> SceneEstimator::associateDetections(const Keyframe& kf,
                                                     const ScoredDetections& detections, int t,
                                                     std::vector<int>* started,
                                                     std::vector<int>* contests) {
  const Eigen::Isometry3d& T_map_cam = T_map_cam_.back();
  std::vector<int> assignment =
      associate(associationLikelihood(kf, detections), config_.association);
  const std::vector<int> contested = contestClasses(kf, detections, t, &assignment);
  std::vector<int> detection_object(kf.detections.size(), -1);
  for (std::size_t r = 0; r < detections.usable.size(); ++r) {
    const std::size_t k = static_cast<std::size_t>(detections.usable[r]);
    const Eigen::Isometry3d& T_cam_obj = detections.pose(k);
    const Observation obs{t, T_cam_obj, detections.score[k], detections.refinement[k].accepted()};
    if (assignment[r] < 0) started->push_back(next_id_);
    Track& tr = assignment[r] < 0 ? startTrack(detections.models[k], T_map_cam * T_cam_obj, t)
                                  : tracks_[static_cast<std::size_t>(assignment[r])];
    detection_object[k] = tr.id;
    (*contests)[k] = contested[r];
    tr.last_keyframe = t;
    if (contested[r] == 1) continue;  // the depth kept the object's class: not its measurement
    if (contested[r] == 0) ++tr.class_evidence[tr.model->name].votes;  // (a challenger's: counted)
    tr.observations.push_back(obs);
    // Without stage I (R-Front): the pose of the most consistent measurement, through odometry.
    if (!stages_.stage_one && obs.consistency >= tr.best_consistency) {
      tr.T_stage_one = tr.T_refined = T_map_cam * T_cam_obj;
    }
    tr.best_consistency = std::max(tr.best_consistency, obs.consistency);
  }
  return detection_object;
}

// Issue 51: a look-alike reported in place of an object (the detection and the object would be
// one object mapped twice, mappedTwice) is the detector naming it otherwise. Both models are
// scored against this keyframe's depth, each at its pose, and the object keeps its class or takes
// the detection's by their support (challengerWins); a class change is logged in the
// detection's decision (class_changed) and counted on the object.
std::vector<int> SceneEstimator::contestClasses(const Keyframe& kf,
                                                const ScoredDetections& detections, int t,
                                                std::vector<int>* assignment) {
  std::vector<int> out(detections.usable.size(), 0);
  const AssociationConfig& c = config_.association;
  if (!c.class_by_consistency || !stages_.class_by_consistency || !kf.depth.data) return out;
  std::vector<char> taken(tracks_.size(), 0);
  for (int j : *assignment)
    if (j >= 0) taken[static_cast<std::size_t>(j)] = 1;
  const Eigen::Isometry3d& T_map_cam = T_map_cam_.back();
  for (std::size_t r = 0; r < detections.usable.size(); ++r) {
    if ((*assignment)[r] >= 0) continue;
    const std::size_t k = static_cast<std::size_t>(detections.usable[r]);
    const std::shared_ptr<const ObjectModel>& model = detections.models[k];
    const Eigen::Isometry3d T_map_det = T_map_cam * detections.pose(k);
    const Track as_object = makeTrack(-1, model, T_map_det, t);
    for (std::size_t j = 0; j < tracks_.size(); ++j) {
      Track& tr = tracks_[j];
      if (taken[j] || tr.model->name == model->name ||
          (reportedPose(tr).translation() - T_map_det.translation()).norm() > 0.15 ||
          !mappedTwice(as_object, T_map_det, tr, reportedPose(tr), c, collider_.get()))
        continue;
      const double f_held =
          scorer_->score(tr.model, T_map_cam.inverse() * reportedPose(tr), kf.depth, kf.K).score;
      taken[j] = 1;
      (*assignment)[r] = static_cast<int>(j);
      out[r] = 1;
      if (challengerWins(&tr, model->name, detections.score[k], f_held, c.class_vote_weight)) {
        changeClass(&tr, model);
        out[r] = 2;
      }
      break;
    }
  }
  return out;
}

// Likelihood of detection r (rows: usable detections) being object j: label indicator x score x
// pose factor of the object's predicted pose in the camera.
Eigen::MatrixXd SceneEstimator::associationLikelihood(const Keyframe& kf,
                                                      const ScoredDetections& detections) const {
  const Eigen::Isometry3d T_cam_map = T_map_cam_.back().inverse();
  Eigen::MatrixXd likelihood =
      Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(detections.usable.size()),
                            static_cast<Eigen::Index>(tracks_.size()));
  for (std::size_t r = 0; r < detections.usable.size(); ++r) {
    const std::size_t k = static_cast<std::size_t>(detections.usable[r]);
    const ObjectMeasurement& d = kf.detections[k];
    for (std::size_t j = 0; j < tracks_.size(); ++j) {
      const Track& tr = tracks_[j];
      if (tr.model->name != d.class_name) continue;
      const Eigen::Isometry3d predicted = T_cam_map * reportedPose(tr);
      likelihood(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(j)) =
          detections.score[k] *
          poseLikelihood(tr.model->symmetry, predicted, detections.pose(k), config_.association);
    }
  }
  return likelihood;
}

SceneEstimator::Track& SceneEstimator::startTrack(const std::shared_ptr<const ObjectModel>& model,
                                                  const Eigen::Isometry3d& T_map_obj, int t) {
  tracks_.push_back(makeTrack(next_id_++, model, T_map_obj, t));
  return tracks_.back();
}

bool SceneEstimator::stageOneDue(int t) const {
  return (t + 1) % std::max(1, config_.stage_one.every_n_keyframes) == 0;
}

std::vector<std::size_t> SceneEstimator::reportedTracks() const {
  std::vector<std::size_t> out;
  for (std::size_t j = 0; j < tracks_.size(); ++j)
    if (tracks_[j].confirmed || !stages_.false_positive_removal) out.push_back(j);
  return out;
}

// Issue 51: a detector that reads a can's label sees the angle about its axis that the depth
// cannot. Where the track's detections in stage I's window agree about it (resultant at least
// stage_one.axis_agreement_min), the estimate is turned onto their weighted circular mean and
// optimised with the model's appearance symmetry; where they scatter the axis stays free. No
// detections in the window: the track keeps what it had.
void SceneEstimator::settleSymmetryAxis(Track* tr) {
  const StageOneConfig& c = config_.stage_one;
  if (!c.axis_from_detections || !tr->model || !axisSeenByDetector(*tr->model)) {
    tr->appearance_model.reset();
    return;
  }
  std::vector<AxialSample> samples;
  for (const Observation& o : tr->observations) {
    if (o.folded || o.gated || o.keyframe < 0 || o.keyframe >= static_cast<int>(T_map_cam_.size()))
      continue;
    const Eigen::Isometry3d T = T_map_cam_[static_cast<std::size_t>(o.keyframe)] * o.T_cam_obj;
    samples.push_back({T.linear(), std::max(o.consistency, 0.05)});
  }
  const AxialAgreement a = axialAgreement(*tr->model, tr->T_stage_one.linear(), samples);
  if (a.samples == 0) return;
  if (a.resultant < c.axis_agreement_min) {
    tr->appearance_model.reset();
    return;
  }
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(-a.mean_rad, tr->model->symmetry.axis.normalized()).toRotationMatrix();
  tr->T_stage_one.linear() = tr->T_stage_one.linear() * turn;
  tr->T_refined.linear() = tr->T_refined.linear() * turn;
  tr->appearance_model = appearance_models_.of(tr->model);
}

StageOneMeasurement SceneEstimator::stageOneMeasurement(const Track& track, const Observation& o,
                                                        int object) const {
  return {o.keyframe, object, o.T_cam_obj, o.gated ? 0.0 : 1.0 / track.variance,
          o.refined ? config_.refinement.ray_sigma_m : 0.0};
}

FoldedMeasurements SceneEstimator::historyOf(const Track& track) const {
  FoldedMeasurements history = track.folded;
  for (const Observation& o : track.observations) {
    if (o.folded || o.keyframe < 0 || o.keyframe >= static_cast<int>(T_map_cam_.size())) continue;
    history.add(T_map_cam_[static_cast<std::size_t>(o.keyframe)], stageOneMeasurement(track, o, 0),
                track.symmetryModel(), track.T_stage_one.linear(), config_.stage_one);
  }
  return history;
}

KeyframeResult SceneEstimator::withHistory(KeyframeResult r) const {
  for (ObjectEstimate& e : r.objects) {
    for (const Track& tr : tracks_)
      if (tr.id == e.id) e.history = historyOf(tr);
  }
  return r;
}

StageReport SceneEstimator::runStageOne() {
  StageOneConfig config = config_.stage_one;
  config.odometry_sigma_position_m *= std::sqrt(odometry_variance_);
  config.odometry_sigma_rotation_rad *= std::sqrt(odometry_variance_);
  // Marginalising outside the window, the observations of cameras before the window's anchor
  // are folded into their object's prior once, and stage I and the noise adaptation see the
  // window's only.
  const int first = static_cast<int>(firstKeyframeInProblem(T_map_cam_.size(), config));
  std::vector<Eigen::Isometry3d> objects;
  std::vector<const ObjectModel*> models;
  std::vector<FoldedMeasurements> folded;
  std::vector<StageOneMeasurement> measurements;
  std::vector<std::pair<std::size_t, std::size_t>> sources;  // (track, observation)
  const std::vector<std::size_t> reported = reportedTracks();
  for (std::size_t i = 0; i < reported.size(); ++i) {
    Track& tr = tracks_[reported[i]];
    settleSymmetryAxis(&tr);
    for (std::size_t k = 0; k < tr.observations.size(); ++k) {
      Observation& o = tr.observations[k];
      if (o.folded) continue;
      const StageOneMeasurement m = stageOneMeasurement(tr, o, static_cast<int>(i));
      if (o.keyframe < first) {
        tr.folded.add(T_map_cam_[static_cast<std::size_t>(o.keyframe)], m, tr.symmetryModel(),
                      tr.T_stage_one.linear(), config);
        o.folded = true;
        continue;
      }
      measurements.push_back(m);
      sources.emplace_back(reported[i], k);
    }
    objects.push_back(tr.T_stage_one);
    models.push_back(tr.symmetryModel());
    folded.push_back(tr.folded);
  }
  const StageOneSummary s =
      optimizeStageOne(&T_map_cam_, T_odom_cam_, &objects, models, measurements, config, &folded);
  if (s.solved) {
    for (std::size_t i = 0; i < reported.size(); ++i) tracks_[reported[i]].T_stage_one = objects[i];
    if (stages_.stage_one_noise_adaptation && config_.stage_one.adapt_noise)
      adaptNoise(reported, objects, models, measurements, sources);
  }
  return {s.status, s.iterations, s.initial_cost, s.final_cost};
}

// Variance component estimation from the residuals of the solve (under the configured noise):
// the odometry's variance factor from the median over its factors (tighter only), each object's
// from the median over its measurements (looser only); a measurement beyond the gate under its
// object's noise is left out of the next solve. Medians of chi-square(6) residuals, 5.35 when the
// configured noise is right.
void SceneEstimator::adaptNoise(const std::vector<std::size_t>& reported,
                                const std::vector<Eigen::Isometry3d>& objects,
                                const std::vector<const ObjectModel*>& models,
                                const std::vector<StageOneMeasurement>& measurements,
                                const std::vector<std::pair<std::size_t, std::size_t>>& sources) {
  const StageOneConfig& c = config_.stage_one;
  constexpr double kMedianChi2of6 = 5.35;
  std::vector<StageOneMeasurement> unit = measurements;
  for (StageOneMeasurement& m : unit) m.weight = 1.0;
  const StageOneResiduals r = stageOneResiduals(T_map_cam_, T_odom_cam_, objects, models, unit, c,
                                                firstKeyframeInProblem(T_map_cam_.size(), c));
  if (!r.odometry.empty()) {
    odometry_variance_ = std::clamp(percentile(r.odometry, 0.5) / kMedianChi2of6,
                                    c.min_odometry_variance_factor, 1.0);
  }
  std::vector<std::vector<double>> per_object(reported.size());
  for (std::size_t i = 0; i < measurements.size(); ++i)
    per_object[static_cast<std::size_t>(measurements[i].object)].push_back(r.measurements[i]);
  for (std::size_t j = 0; j < reported.size(); ++j) {
    if (per_object[j].empty()) continue;
    tracks_[reported[j]].variance = std::clamp(percentile(per_object[j], 0.5) / kMedianChi2of6, 1.0,
                                               c.max_object_variance_factor);
  }
  for (std::size_t i = 0; i < measurements.size(); ++i) {
    Track& tr = tracks_[sources[i].first];
    tr.observations[sources[i].second].gated = r.measurements[i] / tr.variance > c.gate_chi2;
  }
}

bool SceneEstimator::recentlySeen(const Track& track) const {
  const int window = config_.stage_two.local_map_keyframes;
  return window <= 0 || track.last_keyframe >= static_cast<int>(T_map_cam_.size()) - window;
}

std::vector<std::size_t> SceneEstimator::localMap(const std::vector<std::size_t>& reported,
                                                  bool everything) const {
  std::vector<char> local(reported.size(), 0);
  std::map<int, std::size_t> position;  // track id -> position in reported
  for (std::size_t i = 0; i < reported.size(); ++i) {
    const Track& tr = tracks_[reported[i]];
    position[tr.id] = i;
    local[i] = everything || recentlySeen(tr);
  }
  // Contact partners of recently seen objects join them (one step, from the last keyframe).
  std::vector<char> partner = local;
  for (const std::pair<int, int>& pair : held_contacts_) {
    const auto a = position.find(pair.first), b = position.find(pair.second);
    if (a == position.end() || b == position.end()) continue;
    if (local[a->second]) partner[b->second] = 1;
    if (local[b->second]) partner[a->second] = 1;
  }
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < reported.size(); ++i)
    if (partner[i]) out.push_back(i);
  return out;
}

void SceneEstimator::updateSupportPlane(const Keyframe& kf) {
  if (!kf.depth.data) return;
  // Searched half-way through each period: not on the keyframes where stage I runs (every
  // stage_one.every_n_keyframes-th, the same 10 by default), so the two costs do not add up.
  const std::size_t n =
      static_cast<std::size_t>(std::max(1, config_.support_plane.search_every_n_keyframes));
  const bool search = T_map_cam_.size() % n == n / 2;
  fuseSupportPlane(estimateSupportPlane(kf.depth, kf.K, T_map_cam_.back(), config_.gravity,
                                        config_.support_plane, search ? nullptr : &support_),
                   &support_);
  if (support_.valid)
    support_model_ =
        supportPlaneModel(support_, &T_map_support_, config_.support_plane.thickness_m);
}

StageReport SceneEstimator::runRelationsAndStageTwo(const Keyframe* kf, StageTimings* timings) {
  auto t0 = Clock::now();
  if (kf) updateSupportPlane(*kf);
  // Relations from the stage I poses (the paper's order: stage I, relations, stage II), over the
  // local map; the contacts among the other objects stay as they were. From the previous
  // keyframe's refined poses, a contact stage II had made held itself (bench: side F1 0.757 and
  // 0.627 against 0.848 and 0.708 from stage I, docs/BENCHMARK.md).
  const std::vector<std::size_t> reported = reportedTracks();
  const std::vector<std::size_t> local = localMap(reported, kf == nullptr);
  std::vector<PosedModel> posed;
  std::map<int, int> local_of_id = {{-1, -1}};
  for (std::size_t i = 0; i < local.size(); ++i) {
    const Track& tr = tracks_[reported[local[i]]];
    posed.push_back({tr.model.get(), tr.T_stage_one});
    local_of_id[tr.id] = static_cast<int>(i);
  }
  std::vector<ObjectPair> held;
  for (const std::pair<int, int>& pair : held_contacts_) {
    const auto a = local_of_id.find(pair.first), b = local_of_id.find(pair.second);
    if (a != local_of_id.end() && b != local_of_id.end())
      held.emplace_back(std::min(a->second, b->second), std::max(a->second, b->second));
  }
  PosedModel ground{support_model_.get(), T_map_support_};
  const std::vector<FeatureContact> local_contacts = inferRelations(
      posed, support_model_ ? &ground : nullptr, config_.gravity, config_.contacts, held);
  setContacts(local_contacts, local, reported);
  if (timings) timings->relations_ms = msSince(t0);

  t0 = Clock::now();
  const StageTwoSummary s =
      solveStageTwo(local, reported, local_contacts, support_model_ ? &ground : nullptr, !kf);
  // The final solve's physical check: what it drops is seated, and checked again. The map's
  // contacts stay those found at the stage I poses (replacing a seated object's with those where
  // it came to rest was measured worse: docs/stability.md).
  std::vector<FeatureContact> seated = local_contacts;
  for (int round = 0; !kf && round < config_.stage_two.seating_rounds; ++round)
    if (!seatDropped(local, reported, support_model_ ? &ground : nullptr, &seated)) break;
  if (!kf && config_.stage_two.physics_contacts && support_model_ && support_.valid)
    setContacts(physicsAgreedContacts(local, reported, local_contacts), local, reported);
  // Candidates follow their stage I / initial pose.
  for (Track& tr : tracks_)
    if (!tr.confirmed) tr.T_refined = tr.T_stage_one;
  if (timings) timings->stage_two_ms = msSince(t0);
  return {s.status, s.iterations, s.initial_cost, s.final_cost};
}

void SceneEstimator::setContacts(const std::vector<FeatureContact>& local_contacts,
                                 const std::vector<std::size_t>& local,
                                 const std::vector<std::size_t>& reported) {
  std::set<int> local_ids = {-1}, reported_ids = {-1};
  std::map<int, int> reported_of_id = {{-1, -1}};
  for (std::size_t i : local) local_ids.insert(tracks_[reported[i]].id);
  for (std::size_t i = 0; i < reported.size(); ++i) {
    reported_ids.insert(tracks_[reported[i]].id);
    reported_of_id[tracks_[reported[i]].id] = static_cast<int>(i);
  }
  std::vector<FeatureContact> by_id;
  auto local_id = [&](int i) { return i < 0 ? -1 : tracks_[reported[local[i]]].id; };
  for (FeatureContact c : local_contacts) {
    c.object_a = local_id(c.object_a), c.object_b = local_id(c.object_b);
    by_id.push_back(c);
  }
  // Kept: the contacts the relations could not find again (an end outside the local map; the
  // support is in it) between objects that still exist.
  for (const FeatureContact& c : contacts_by_id_) {
    const bool found_again = local_ids.count(c.object_a) && local_ids.count(c.object_b);
    if (found_again || !reported_ids.count(c.object_a) || !reported_ids.count(c.object_b)) continue;
    by_id.push_back(c);
  }
  contacts_by_id_ = by_id;
  contacts_.clear();
  held_contacts_.clear();
  for (FeatureContact c : by_id) {
    held_contacts_.emplace_back(std::min(c.object_a, c.object_b), std::max(c.object_a, c.object_b));
    c.object_a = reported_of_id[c.object_a], c.object_b = reported_of_id[c.object_b];
    contacts_.push_back(c);
  }
}

bool SceneEstimator::seatDropped(const std::vector<std::size_t>& local,
                                 const std::vector<std::size_t>& reported, const PosedModel* ground,
                                 std::vector<FeatureContact>* contacts) {
  if (!ground || !support_.valid) return false;  // no plane: nothing to seat anything on
  const StageTwoConfig& config = config_.stage_two;
  std::vector<Track*> solved;
  for (std::size_t i : local) solved.push_back(&tracks_[reported[i]]);
  const physics::StabilityResult check = checkLocalStability(local, reported);
  // Each object where the simulation left it, if it dropped it within the bounds.
  std::vector<PosedModel> rested;
  std::vector<bool> dropped(solved.size(), false);
  for (std::size_t i = 0; i < solved.size(); ++i) {
    const physics::BodyMotion& m = check.bodies[i];
    dropped[i] = m.simulated && !m.interpenetrating && !m.stable &&
                 m.translation_m < config.seat_max_translation_m &&
                 m.rotation_deg < config.seat_max_rotation_deg;
    rested.push_back({solved[i]->model.get(), dropped[i] ? m.T_world_end : solved[i]->T_refined});
  }
  auto none_dropped = [&dropped] {
    return std::none_of(dropped.begin(), dropped.end(), [](bool d) { return d; });
  };
  if (none_dropped()) return false;  // everything stands: no relations to look for
  // The contacts where they came to rest; one that has none there is not seated.
  const std::vector<FeatureContact> found = restingContacts(&rested, &dropped, solved, ground);
  if (none_dropped()) return false;
  auto touches_dropped = [&](const FeatureContact& c) {
    return (c.object_a >= 0 && dropped[c.object_a]) || (c.object_b >= 0 && dropped[c.object_b]);
  };
  contacts->erase(std::remove_if(contacts->begin(), contacts->end(), touches_dropped),
                  contacts->end());
  contacts->insert(contacts->end(), found.begin(), found.end());
  // Stage II again (with its separation rounds), the dropped objects starting where they came
  // to rest: seated on those contacts against their stage I priors, parted from what they reach.
  std::vector<Eigen::Isometry3d> before;
  const std::vector<Separation> separations_before = separations_by_id_;
  for (std::size_t i = 0; i < solved.size(); ++i) {
    before.push_back(solved[i]->T_refined);
    if (dropped[i]) solved[i]->T_refined = rested[i].T_world_obj;
  }
  if (solveStageTwo(local, reported, *contacts, ground, true).solved) return true;
  for (std::size_t i = 0; i < solved.size(); ++i) solved[i]->T_refined = before[i];
  separations_by_id_ = separations_before;
  return false;
}

physics::StabilityResult SceneEstimator::checkLocalStability(
    const std::vector<std::size_t>& local, const std::vector<std::size_t>& reported) const {
  std::vector<physics::StabilityBody> bodies;
  for (std::size_t i : local) {
    const Track& tr = tracks_[reported[i]];
    bodies.push_back({tr.id, tr.model, tr.T_refined});
  }
  const physics::StabilityPlane plane{support_.normal, support_.height};
  return physics::checkStability(bodies, &plane, config_.gravity, config_.physics);
}

std::vector<FeatureContact> SceneEstimator::physicsAgreedContacts(
    const std::vector<std::size_t>& local, const std::vector<std::size_t>& reported,
    const std::vector<FeatureContact>& contacts) const {
  const physics::StabilityResult check = checkLocalStability(local, reported);
  auto judged = [&check](int k) {
    if (k < 0) return true;  // the plane
    const physics::BodyMotion& m = check.bodies[static_cast<std::size_t>(k)];
    return m.simulated && !m.interpenetrating && m.stable;
  };
  auto id_of = [&check](int k) {
    return k < 0 ? physics::kPlaneId : check.bodies[static_cast<std::size_t>(k)].id;
  };
  const StageTwoConfig& config = config_.stage_two;
  std::vector<FeatureContact> kept;
  for (const FeatureContact& c : contacts) {
    const physics::RestContact* rest = check.restContact(id_of(c.object_a), id_of(c.object_b));
    const bool agrees = rest && (c.kind == ContactKind::kSide
                                     ? rest->min_distance_m <= config.physics_side_max_distance_m
                                     : rest->normal_force_N >= config.physics_min_force);
    if (agrees || !judged(c.object_a) || !judged(c.object_b)) kept.push_back(c);
  }
  return kept;
}

std::vector<FeatureContact> SceneEstimator::restingContacts(std::vector<PosedModel>* rested,
                                                            std::vector<bool>* dropped,
                                                            const std::vector<Track*>& solved,
                                                            const PosedModel* ground) const {
  std::vector<FeatureContact> found;
  for (bool changed = true; changed;) {
    found.clear();
    std::vector<bool> touched(solved.size(), false);
    for (const FeatureContact& c :
         inferRelations(*rested, ground, config_.gravity, config_.contacts, {})) {
      const bool a = c.object_a >= 0 && (*dropped)[c.object_a];
      const bool b = c.object_b >= 0 && (*dropped)[c.object_b];
      if (!a && !b) continue;
      found.push_back(c);
      if (a) touched[c.object_a] = true;
      if (b) touched[c.object_b] = true;
    }
    changed = false;
    for (std::size_t i = 0; i < solved.size(); ++i) {
      if (!(*dropped)[i] || touched[i]) continue;
      (*dropped)[i] = false;  // nothing holds it where it came to rest: left where it was
      (*rested)[i].T_world_obj = solved[i]->T_refined;
      changed = true;
    }
  }
  return found;
}

std::vector<Separation> SceneEstimator::localSeparations(const std::map<int, int>& index_of_id,
                                                         const std::vector<Track*>& solved,
                                                         bool has_ground) const {
  const StageTwoConfig& config = config_.stage_two;
  std::vector<CollisionBody> stage_one;  // where a carried separation is checked again
  for (const Track* tr : solved) stage_one.push_back({tr->model, tr->T_stage_one});
  std::vector<Separation> separations;  // local indices
  for (Separation s : separations_by_id_) {
    const auto a = index_of_id.find(s.object_a), b = index_of_id.find(s.object_b);
    if (config.separation_rounds == 0 || a == index_of_id.end() || b == index_of_id.end() ||
        (s.object_a < 0 && !has_ground))
      continue;
    s.object_a = a->second, s.object_b = b->second;
    if (config.separation_drop_stale &&
        !stillInterpenetrating(s, stage_one, support_, config.separation_min_depth_m,
                               collider_.get()))
      continue;
    separations.push_back(s);
  }
  return separations;
}

namespace {

// How far the pair of a separation is from parting (negative: parted by that much), at the poses
// of its bodies (`T_a` for the ground: its block's pose).
double shortOfParting(const Separation& s, const Eigen::Isometry3d& T_a,
                      const Eigen::Isometry3d& T_b, double margin_m) {
  return s.depth + margin_m - s.normal.dot(T_b * s.p_b - T_a * s.p_a);
}

// The objects a re-solve holds (true): all but those of the `found` separations and their
// neighbours in the `contacts`, which move with them.
std::vector<bool> heldOutside(const std::vector<Separation>& found,
                              const std::vector<FeatureContact>& contacts, std::size_t n) {
  std::vector<bool> moving(n, false);
  for (const Separation& s : found)
    for (int i : {s.object_a, s.object_b})
      if (i >= 0) moving[static_cast<std::size_t>(i)] = true;
  std::vector<bool> held(n);
  for (std::size_t i = 0; i < n; ++i) held[i] = !moving[i];
  for (const FeatureContact& c : contacts) {
    const int a = c.object_a, b = c.object_b;
    if (a < 0 || b < 0) continue;
    const std::size_t ua = static_cast<std::size_t>(a), ub = static_cast<std::size_t>(b);
    if (ua >= n || ub >= n) continue;
    if (moving[ua]) held[ub] = false;
    if (moving[ub]) held[ua] = false;
  }
  return held;
}

}  // namespace

StageTwoSummary SceneEstimator::solveStageTwo(const std::vector<std::size_t>& local,
                                              const std::vector<std::size_t>& reported,
                                              const std::vector<FeatureContact>& contacts,
                                              const PosedModel* ground, bool final_solve) {
  std::vector<Eigen::Isometry3d> poses, priors;
  std::vector<double> prior_weights;
  std::vector<const ObjectModel*> models;
  std::vector<Track*> solved;
  std::map<int, int> index_of_id = {{-1, -1}};
  for (std::size_t i : local) {
    Track& tr = tracks_[reported[i]];
    index_of_id[tr.id] = static_cast<int>(solved.size());
    poses.push_back(tr.T_refined);
    priors.push_back(tr.T_stage_one);
    prior_weights.push_back(priorWeight(tr.measurementCount(), config_.stage_two));
    models.push_back(tr.symmetryModel());
    solved.push_back(&tr);
  }
  const StageTwoConfig& config = config_.stage_two;
  std::vector<Separation> separations = localSeparations(index_of_id, solved, ground != nullptr);
  StageTwoSummary s;
  std::vector<bool> held;  // the first solve: every object
  for (int round = 0; round <= config.separation_rounds; ++round) {
    if (round > 0) {  // what still interpenetrates parts, and its part of the scene is re-solved
      std::vector<CollisionBody> bodies;
      for (const Track* tr : solved) bodies.push_back({tr->model, tr->T_refined});
      const std::vector<Separation> found = findInterpenetrations(
          bodies, ground ? &support_ : nullptr, T_map_support_, config.separation_min_depth_m,
          collider_.get(), final_solve,
          final_solve && !config_.physics.convex_parts ? config.separation_hull_max_depth_m : 0.0);
      if (found.empty()) break;
      separations.insert(separations.end(), found.begin(), found.end());
      held = heldOutside(found, contacts, solved.size());
      for (std::size_t i = 0; i < solved.size(); ++i) poses[i] = solved[i]->T_refined;
    }
    const StageTwoSummary r = optimizeStageTwo(&poses, models, priors, contacts, ground, config,
                                               separations, held, prior_weights);
    if (round == 0) {
      s = r;
    } else {  // a re-solve: its iterations count, the costs stay the first solve's
      s.iterations += r.iterations;
      s.separations = r.separations;
      if (!r.solved) s.status = r.status;
      if (!r.solved) break;  // the first solve's poses stay
    }
    for (std::size_t i = 0; i < solved.size(); ++i) {
      solved[i]->T_refined = poses[i];
      liftOutOfSupport(solved[i]);
    }
  }
  keepSeparations(separations, solved);
  return s;
}

// Nothing stays in the table: an estimate through its top deeper than a contact can resolve
// rests on it instead.
void SceneEstimator::liftOutOfSupport(Track* track) const {
  if (!config_.stage_two.lift_out_of_support) return;
  const double depth = depthThroughPlane(support_, *track->model, track->T_refined);
  if (depth > config_.contacts.max_penetration_m)
    track->T_refined.translation() += depth * support_.normal;
}

// The separations among `solved` (local indices) replace those carried between them; one within
// a centimetre of parting is carried on (by track ids), unless its pair is of one class.
void SceneEstimator::keepSeparations(const std::vector<Separation>& separations,
                                     const std::vector<Track*>& solved) {
  std::set<int> in_solve = {-1};
  for (const Track* tr : solved) in_solve.insert(tr->id);
  std::vector<Separation> kept;
  for (const Separation& s : separations_by_id_)
    if (!in_solve.count(s.object_a) || !in_solve.count(s.object_b)) kept.push_back(s);
  for (Separation s : separations) {
    const Track& b = *solved[static_cast<std::size_t>(s.object_b)];
    const Eigen::Isometry3d T_a =
        s.object_a < 0 ? T_map_support_ : solved[static_cast<std::size_t>(s.object_a)]->T_refined;
    if (shortOfParting(s, T_a, b.T_refined, config_.stage_two.separation_margin_m) < -0.01)
      continue;
    // A pair of one class (parted by the final solve) is not carried: merging decides on it.
    if (s.object_a >= 0 && solved[static_cast<std::size_t>(s.object_a)]->model && b.model &&
        solved[static_cast<std::size_t>(s.object_a)]->model->name == b.model->name)
      continue;
    s.object_a = s.object_a < 0 ? -1 : solved[static_cast<std::size_t>(s.object_a)]->id;
    s.object_b = b.id;
    kept.push_back(s);
  }
  separations_by_id_ = kept;
}

KeyframeResult SceneEstimator::snapshot() const {
  return withHistory(
      result(static_cast<int>(T_map_cam_.size()) - 1, stamps_.empty() ? 0.0 : stamps_.back()));
}

KeyframeResult SceneEstimator::finish() {
  const auto start = Clock::now();
  StageTimings timings;
  StageReport stage_one, stage_two;
  if (stages_.stage_one && !T_map_cam_.empty()) {
    const auto t0 = Clock::now();
    stage_one = runStageOne();
    timings.stage_one_ms = msSince(t0);
  }
  if (stages_.relations_and_stage_two) stage_two = runRelationsAndStageTwo(nullptr, &timings);
  KeyframeResult out = withHistory(
      result(static_cast<int>(T_map_cam_.size()) - 1, stamps_.empty() ? 0.0 : stamps_.back()));
  out.stage_one = stage_one;
  out.stage_two = stage_two;
  timings.total_ms = msSince(start);
  out.timings = timings;
  return out;
}

}  // namespace geofusion
