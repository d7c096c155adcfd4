#include "geofusion/estimation/run_results.h"

#include "geofusion/common/yaml_io.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <stdexcept>

namespace geofusion {
namespace {

// An object's stage I history (a saved map's; ObjectEstimate::history): its folded mean, the
// translation's information (upper triangle, row by row) and the rotation's.
void emitHistory(YAML::Emitter& out, const FoldedMeasurements& h) {
  out << YAML::Key << "stage_one_prior" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "measurements" << YAML::Value << h.count();
  yaml_io::emitPose(out, "mean", h.mean());
  const Eigen::Matrix3d& I = h.translationInformation();
  out << YAML::Key << "translation_information" << YAML::Value << YAML::Flow << YAML::BeginSeq
      << I(0, 0) << I(0, 1) << I(0, 2) << I(1, 1) << I(1, 2) << I(2, 2) << YAML::EndSeq;
  out << YAML::Key << "rotation_information" << YAML::Value << h.rotationInformation();
  out << YAML::EndMap;
}

FoldedMeasurements readHistory(const YAML::Node& h) {
  const YAML::Node t = h["translation_information"];
  if (!t || !t.IsSequence() || t.size() != 6)
    throw std::runtime_error("stage_one_prior: translation_information needs 6 values");
  Eigen::Matrix3d I;
  I << t[0].as<double>(), t[1].as<double>(), t[2].as<double>(), t[1].as<double>(),
      t[3].as<double>(), t[4].as<double>(), t[2].as<double>(), t[4].as<double>(), t[5].as<double>();
  const FoldedMeasurements f = FoldedMeasurements::fromPrior(
      yaml_io::parsePose(h["mean"], "stage_one_prior: mean"), I,
      h["rotation_information"].as<double>(), h["measurements"].as<int>());
  if (f.empty())
    throw std::runtime_error("stage_one_prior: its information is not positive definite");
  return f;
}

void emitObjects(YAML::Emitter& out, const std::vector<ObjectEstimate>& objects,
                 const Eigen::Isometry3d& T_map_cam) {
  out << YAML::Key << "objects" << YAML::Value << YAML::BeginSeq;
  const Eigen::Isometry3d T_cam_map = T_map_cam.inverse();
  for (const ObjectEstimate& o : objects) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "id" << YAML::Value << o.id;
    out << YAML::Key << "class_name" << YAML::Value << (o.model ? o.model->name : "");
    out << YAML::Key << "class_id" << YAML::Value << (o.model ? o.model->id : -1);
    out << YAML::Key << "score" << YAML::Value << o.existence;
    out << YAML::Key << "false_positive" << YAML::Value << o.false_positive;
    out << YAML::Key << "consistency" << YAML::Value << o.best_consistency;
    out << YAML::Key << "measurements" << YAML::Value << o.measurements;
    yaml_io::emitPose(out, "map_object", o.T_map_obj);
    yaml_io::emitPose(out, "camera_object", T_cam_map * o.T_map_obj);
    if (!o.history.empty()) emitHistory(out, o.history);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

void emitContacts(YAML::Emitter& out, const KeyframeResult& r) {
  out << YAML::Key << "contacts" << YAML::Value << YAML::BeginSeq;
  for (const FeatureContact& c : r.contacts) {
    auto id = [&](int index) {
      return index < 0 || index >= static_cast<int>(r.objects.size())
                 ? -1
                 : r.objects[static_cast<std::size_t>(index)].id;
    };
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "a" << YAML::Value << id(c.object_a);  // -1: the support plane
    out << YAML::Key << "b" << YAML::Value << id(c.object_b);
    out << YAML::Key << "type" << YAML::Value << shortName(c.type);
    out << YAML::Key << "kind" << YAML::Value << toString(c.kind);
    out << YAML::Key << "distance_residual" << YAML::Value << c.distance_residual;
    // From a towards b: which of a leaning pair leans (scene_graph.h).
    out << YAML::Key << "normal" << YAML::Value << YAML::Flow
        << std::vector<double>{c.normal.x(), c.normal.y(), c.normal.z()};
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

// The final map's scene graph: the removal order, then per object its relations (ids, -1 the
// support plane), whether it stands (-1: not checked) and whether it is free to pick.
void emitSceneGraph(YAML::Emitter& out, const SupportGraph& g) {
  out << YAML::Key << "scene_graph" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "removal_order" << YAML::Value << YAML::Flow << g.removal_order;
  out << YAML::Key << "objects" << YAML::Value << YAML::BeginSeq;
  for (const SupportGraphNode& n : g.nodes) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "id" << YAML::Value << n.id;
    out << YAML::Key << "class" << YAML::Value << n.class_name;
    out << YAML::Key << "supported_by" << YAML::Value << YAML::Flow << n.supported_by;
    out << YAML::Key << "supports" << YAML::Value << YAML::Flow << n.supports;
    out << YAML::Key << "leans_on" << YAML::Value << YAML::Flow << n.leans_on;
    out << YAML::Key << "leaned_on_by" << YAML::Value << YAML::Flow << n.leaned_on_by;
    out << YAML::Key << "beside" << YAML::Value << YAML::Flow << n.beside;
    out << YAML::Key << "over" << YAML::Value << YAML::Flow << n.over;
    out << YAML::Key << "covered_by" << YAML::Value << YAML::Flow << n.covered_by;
    out << YAML::Key << "stable" << YAML::Value << n.stable;
    out << YAML::Key << "free_to_pick" << YAML::Value << n.free_to_pick;
    out << YAML::Key << "removal_step" << YAML::Value << n.removal_step;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "warnings" << YAML::Value << YAML::Flow << g.warnings;
  out << YAML::EndMap;
}

// The keyframe's relocalisation: whether it searched, what it decided, the correction found, its
// support, the runner-up's, and the odometry drift it was judged against (issue 32).
void emitRelocalisation(YAML::Emitter& out, const Relocalisation& r) {
  out << YAML::Key << "relocalisation" << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "searched" << YAML::Value << r.tried;
  out << YAML::Key << "decision" << YAML::Value << toString(r.decision);
  out << YAML::Key << "detections" << YAML::Value << r.detections;
  out << YAML::Key << "on_map" << YAML::Value << r.inliers_before;
  if (r.tried) {
    out << YAML::Key << "support" << YAML::Value << r.inliers_after;
    out << YAML::Key << "runner_up" << YAML::Value << r.runner_up;
    out << YAML::Key << "mahalanobis_sq" << YAML::Value << r.mahalanobis_sq;
    const bool gated = std::isfinite(r.drift.sigma_m);
    out << YAML::Key << "drift_sigma_m" << YAML::Value << (gated ? r.drift.sigma_m : -1.0);
    out << YAML::Key << "drift_sigma_rad" << YAML::Value << (gated ? r.drift.sigma_rad : -1.0);
    out << YAML::Key << "path_m" << YAML::Value << r.drift.path_m;
    yaml_io::emitPose(out, "correction", r.T_correction);
  }
  out << YAML::EndMap;
}

Relocalisation readRelocalisation(const YAML::Node& n) {
  Relocalisation r;
  if (!n) return r;  // results written before issue 32
  r.tried = n["searched"].as<bool>();
  if (!parseRelocalisationDecision(n["decision"].as<std::string>(), &r.decision))
    throw std::runtime_error("relocalisation: unknown decision '" +
                             n["decision"].as<std::string>() + "'");
  r.applied = r.decision == RelocalisationDecision::kApplied;
  r.detections = n["detections"].as<int>(0);
  r.inliers_before = r.inliers_after = n["on_map"].as<int>(0);
  if (!r.tried) return r;
  r.inliers_after = n["support"].as<int>();
  r.runner_up = n["runner_up"].as<int>();
  r.mahalanobis_sq = n["mahalanobis_sq"].as<double>();
  const double sigma_m = n["drift_sigma_m"].as<double>(),
               sigma_rad = n["drift_sigma_rad"].as<double>();
  if (sigma_m >= 0) r.drift.sigma_m = sigma_m, r.drift.sigma_rad = sigma_rad;
  r.drift.path_m = n["path_m"].as<double>(0.0);
  r.T_correction = yaml_io::parsePose(n["correction"], "correction");
  return r;
}

void emitRemovals(YAML::Emitter& out, const std::vector<Removal>& removals) {
  out << YAML::Key << "removals" << YAML::Value << YAML::BeginSeq;
  for (const Removal& r : removals) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "id" << YAML::Value << r.id;
    out << YAML::Key << "reason" << YAML::Value << toString(r.reason);
    if (r.reason == RemovalReason::kMerged) out << YAML::Key << "into" << YAML::Value << r.into;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

std::vector<Removal> readRemovals(const YAML::Node& n) {
  std::vector<Removal> out;
  for (const YAML::Node& r : n) {
    Removal removal;
    removal.id = r["id"].as<int>();
    if (!parseRemovalReason(r["reason"].as<std::string>(), &removal.reason))
      throw std::runtime_error("removals: unknown reason '" + r["reason"].as<std::string>() + "'");
    removal.into = r["into"].as<int>(-1);
    out.push_back(removal);
  }
  return out;
}

void emitTimings(YAML::Emitter& out, const StageTimings& t) {
  out << YAML::Key << "timings_ms" << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "consistency" << YAML::Value << t.consistency_ms;
  out << YAML::Key << "association" << YAML::Value << t.association_ms;
  out << YAML::Key << "lifecycle" << YAML::Value << t.lifecycle_ms;
  out << YAML::Key << "stage_one" << YAML::Value << t.stage_one_ms;
  out << YAML::Key << "relations" << YAML::Value << t.relations_ms;
  out << YAML::Key << "stage_two" << YAML::Value << t.stage_two_ms;
  out << YAML::Key << "total" << YAML::Value << t.total_ms << YAML::EndMap;
}

// `stages: {stage_one: converged, stage_two: nothing_to_solve}`: the optimisation stages that ran
// at this keyframe and how they ended (a failed stage's result was not used).
void emitStages(YAML::Emitter& out, const KeyframeResult& k) {
  out << YAML::Key << "stages" << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "stage_one" << YAML::Value << toString(k.stage_one.status);
  out << YAML::Key << "stage_two" << YAML::Value << toString(k.stage_two.status);
  out << YAML::EndMap;
}

// `detections:` per input detection: class, detector score, pose in and out (camera frame), the
// refinement's outcome and correction, the consistency at the pose used and the decision.
void emitDetections(YAML::Emitter& out, const std::vector<DetectionReport>& detections) {
  out << YAML::Key << "detections" << YAML::Value << YAML::BeginSeq;
  for (const DetectionReport& d : detections) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "class_name" << YAML::Value << d.class_name;
    out << YAML::Key << "score" << YAML::Value << d.detector_score;
    yaml_io::emitPose(out, "pose_in", d.T_cam_in);
    yaml_io::emitPose(out, "pose_out", d.T_cam_out);
    out << YAML::Key << "refinement" << YAML::Value << toString(d.refinement);
    if (std::isfinite(d.ray_offset_m))
      out << YAML::Key << "ray_offset_m" << YAML::Value << d.ray_offset_m;
    out << YAML::Key << "correction_m" << YAML::Value << d.correction_translation_m;
    out << YAML::Key << "correction_rad" << YAML::Value << d.correction_rotation_rad;
    out << YAML::Key << "consistency" << YAML::Value << d.consistency;
    out << YAML::Key << "ratios" << YAML::Value << YAML::Flow << YAML::BeginSeq << d.r_in << d.r_out
        << d.r_occ << YAML::EndSeq;
    out << YAML::Key << "decision" << YAML::Value << toString(d.decision);
    out << YAML::Key << "object" << YAML::Value << d.object;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

std::vector<DetectionReport> readDetections(const YAML::Node& list) {
  std::vector<DetectionReport> out;
  for (const YAML::Node& n : list) {  // absent in results written before they were reported
    DetectionReport d;
    d.class_name = n["class_name"].as<std::string>();
    d.detector_score = n["score"].as<double>();
    d.T_cam_in = yaml_io::parsePose(n["pose_in"], "detection pose_in");
    d.T_cam_out = yaml_io::parsePose(n["pose_out"], "detection pose_out");
    const std::string refinement = n["refinement"].as<std::string>();
    if (!parseRefinementOutcome(refinement, &d.refinement))
      throw std::runtime_error("detection refinement: unknown outcome '" + refinement + "'");
    d.ray_offset_m = n["ray_offset_m"] ? n["ray_offset_m"].as<double>()
                                       : std::numeric_limits<double>::quiet_NaN();
    d.correction_translation_m = n["correction_m"].as<double>();
    d.correction_rotation_rad = n["correction_rad"].as<double>();
    d.consistency = n["consistency"].as<double>();
    d.r_in = n["ratios"][0].as<double>();
    d.r_out = n["ratios"][1].as<double>();
    d.r_occ = n["ratios"][2].as<double>();
    const std::string decision = n["decision"].as<std::string>();
    if (!parseDetectionDecision(decision, &d.decision))
      throw std::runtime_error("detection decision: unknown '" + decision + "'");
    d.object = n["object"].as<int>();
    out.push_back(std::move(d));
  }
  return out;
}

void readStages(const YAML::Node& n, KeyframeResult* k) {
  if (!n) return;  // results written before the stages were reported
  for (auto [key, report] : {std::pair{"stage_one", &k->stage_one}, {"stage_two", &k->stage_two}}) {
    if (n[key] && !parseSolveStatus(n[key].as<std::string>(), &report->status)) {
      throw std::runtime_error(std::string("stages.") + key + ": unknown status '" +
                               n[key].as<std::string>() + "'");
    }
  }
}

}  // namespace

std::vector<std::pair<std::string, std::size_t>> removalsByReason(const RunResults& results) {
  std::vector<std::pair<std::string, std::size_t>> out;
  for (RemovalReason reason :
       {RemovalReason::kCandidateTimeout, RemovalReason::kSeenAbsent, RemovalReason::kMerged}) {
    std::size_t n = 0;
    for (const KeyframeResult& k : results.keyframes)
      for (const Removal& r : k.removals) n += r.reason == reason;
    out.emplace_back(toString(reason), n);
  }
  return out;
}

std::vector<std::pair<std::string, std::size_t>> relocalisationsByDecision(
    const RunResults& results) {
  std::vector<std::pair<std::string, std::size_t>> out;
  for (RelocalisationDecision d :
       {RelocalisationDecision::kApplied, RelocalisationDecision::kNoGain,
        RelocalisationDecision::kBeyondDrift, RelocalisationDecision::kAmbiguous}) {
    std::size_t n = 0;
    for (const KeyframeResult& k : results.keyframes) n += k.relocalisation.decision == d;
    out.emplace_back(toString(d), n);
  }
  return out;
}

int failedStages(const RunResults& results) {
  int failed = 0;
  auto count = [&](const KeyframeResult& k) {
    failed += (k.stage_one.failed() ? 1 : 0) + (k.stage_two.failed() ? 1 : 0);
  };
  for (const KeyframeResult& k : results.keyframes) count(k);
  count(results.final_map);
  return failed;
}

bool writeRunResults(const std::string& path, const RunResults& r, std::string* error) {
  YAML::Emitter out;
  out.SetDoublePrecision(10);
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << "geofusion_results_v1";
  out << YAML::Key << "method" << YAML::Value << r.method;
  out << YAML::Key << "source" << YAML::Value << r.source;
  out << YAML::Key << "model_set" << YAML::Value << r.model_set;
  if (!r.config_yaml.empty()) {
    out << YAML::Key << "config" << YAML::Value << YAML::Load(r.config_yaml);
  }
  out << YAML::Key << "recording_duration_s" << YAML::Value << r.recording_duration_s;
  out << YAML::Key << "wall_time_s" << YAML::Value << r.wall_time_s;
  out << YAML::Key << "peak_rss_mb" << YAML::Value << r.peak_rss_mb;
  out << YAML::Key << "realtime_factor" << YAML::Value
      << (r.recording_duration_s > 0 ? r.wall_time_s / r.recording_duration_s : 0.0);
  out << YAML::Key << "frames_seen" << YAML::Value << r.frames_seen;
  out << YAML::Key << "frames_skipped" << YAML::Value << r.frames_skipped;
  for (const auto& [key, counts] : {std::pair{"frames_dropped", &r.frames_dropped},
                                    std::pair{"detections_dropped", &r.detections_dropped}}) {
    out << YAML::Key << key << YAML::Value << YAML::BeginMap;
    for (const auto& [reason, n] : *counts) out << YAML::Key << reason << YAML::Value << n;
    out << YAML::EndMap;
  }
  out << YAML::Key << "keyframes_over_budget" << YAML::Value << r.keyframes_over_budget;
  if (r.has_background) {
    const BackgroundStats& b = r.background;
    out << YAML::Key << "background" << YAML::Value << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "keyframes_submitted" << YAML::Value << b.submitted;
    out << YAML::Key << "keyframes_inserted" << YAML::Value << b.inserted;
    out << YAML::Key << "keyframes_skipped" << YAML::Value << b.skipped;
    out << YAML::Key << "keyframes_still" << YAML::Value << b.still;
    out << YAML::Key << "ms_p50" << YAML::Value << b.p50_ms;
    out << YAML::Key << "ms_p95" << YAML::Value << b.p95_ms;
    out << YAML::Key << "ms_max" << YAML::Value << b.max_ms;
    out << YAML::Key << "ms_total" << YAML::Value << b.total_ms;
    out << YAML::Key << "ms_amortised" << YAML::Value << b.amortisedMs();
    out << YAML::EndMap;
  }
  for (const auto& [key, counts] : {std::pair{"removals_by_reason", removalsByReason(r)},
                                    std::pair{"relocalisations", relocalisationsByDecision(r)}}) {
    out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginMap;
    for (const auto& [word, n] : counts) out << YAML::Key << word << YAML::Value << n;
    out << YAML::EndMap;
  }
  out << YAML::Key << "keyframes" << YAML::Value << YAML::BeginSeq;
  for (const KeyframeResult& k : r.keyframes) {
    out << YAML::BeginMap;
    out << YAML::Key << "index" << YAML::Value << k.keyframe;
    char stamp[32];
    std::snprintf(stamp, sizeof(stamp), "%.9f", k.stamp_s);
    out << YAML::Key << "stamp" << YAML::Value << stamp;
    yaml_io::emitPose(out, "map_camera", k.T_map_cam);
    emitTimings(out, k.timings);
    emitStages(out, k);
    out << YAML::Key << "removed_ids" << YAML::Value << YAML::Flow << k.removed_ids;
    emitRemovals(out, k.removals);
    emitRelocalisation(out, k.relocalisation);
    out << YAML::Key << "skipped_detections" << YAML::Value << k.skipped_detections;
    if (!k.detection_warning.empty())
      out << YAML::Key << "detection_warning" << YAML::Value << k.detection_warning;
    emitDetections(out, k.detections);
    emitObjects(out, k.objects, k.T_map_cam);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "final_map" << YAML::Value << YAML::BeginMap;
  emitTimings(out, r.final_map.timings);
  emitStages(out, r.final_map);
  emitObjects(out, r.final_map.objects, r.final_map.T_map_cam);
  emitContacts(out, r.final_map);
  if (r.has_scene_graph) emitSceneGraph(out, r.scene_graph);
  if (r.support_plane.valid) {
    const Eigen::Vector3d& n = r.support_plane.normal;
    out << YAML::Key << "support_plane" << YAML::Value << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "normal" << YAML::Value << YAML::Flow << YAML::BeginSeq << n.x() << n.y()
        << n.z() << YAML::EndSeq;
    out << YAML::Key << "height" << YAML::Value << r.support_plane.height;
    // What a resumed estimator fuses on from (issue 52): the extent and the evidence.
    const SupportPlane& p = r.support_plane;
    out << YAML::Key << "centre" << YAML::Value << YAML::Flow << YAML::BeginSeq << p.centre.x()
        << p.centre.y() << p.centre.z() << YAML::EndSeq;
    out << YAML::Key << "axis_x" << YAML::Value << YAML::Flow << YAML::BeginSeq << p.axes(0, 0)
        << p.axes(1, 0) << p.axes(2, 0) << YAML::EndSeq;
    out << YAML::Key << "size" << YAML::Value << YAML::Flow << YAML::BeginSeq << p.size.x()
        << p.size.y() << YAML::EndSeq;
    out << YAML::Key << "inliers" << YAML::Value << p.inliers;
    out << YAML::Key << "observations" << YAML::Value << p.observations << YAML::EndMap;
  }
  out << YAML::EndMap;
  out << YAML::Key << "trajectory" << YAML::Value << YAML::BeginSeq;
  for (std::size_t i = 0; i < r.trajectory.size(); ++i) {
    out << YAML::Flow << YAML::BeginMap;
    char stamp[32];
    std::snprintf(stamp, sizeof(stamp), "%.9f",
                  i < r.trajectory_stamps.size() ? r.trajectory_stamps[i] : 0.0);
    out << YAML::Key << "stamp" << YAML::Value << stamp;
    yaml_io::emitPose(out, "map_camera", r.trajectory[i]);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  if (!r.map_id.empty()) {
    out << YAML::Key << "map" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "id" << YAML::Value << r.map_id;
    out << YAML::Key << "session" << YAML::Value << r.session;
    out << YAML::Key << "keyframes_total" << YAML::Value << r.keyframes_total;
    out << YAML::Key << "next_object_id" << YAML::Value << r.next_object_id;
    yaml_io::emitPose(out, "map_odom", r.T_map_odom);
    out << YAML::Key << "background" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "file" << YAML::Value << r.background_file;
    out << YAML::Key << "bytes" << YAML::Value << r.background_bytes;
    out << YAML::Key << "fnv1a64" << YAML::Value << r.background_checksum;
    out << YAML::EndMap << YAML::EndMap;
  }
  out << YAML::EndMap;
  return yaml_io::writeAtomically(
      path, "# GeoFusion run results (docs/results.md). Poses [x, y, z, qx, qy, qz, qw].\n", out,
      error);
}

namespace {

std::vector<ObjectEstimate> readObjects(const YAML::Node& list, const ModelSet& models) {
  std::vector<ObjectEstimate> objects;
  for (const YAML::Node& o : list) {
    ObjectEstimate e;
    e.id = o["id"].as<int>();
    const std::string name = o["class_name"].as<std::string>();
    for (const auto& m : models.models())
      if (m->name == name) e.model = m;
    if (!e.model) throw std::runtime_error("class '" + name + "' is not in the model set");
    e.existence = o["score"].as<double>();
    e.false_positive = o["false_positive"].as<double>();
    e.best_consistency = o["consistency"].as<double>();
    e.measurements = o["measurements"].as<int>();
    e.T_map_obj = yaml_io::parsePose(o["map_object"], "map_object");
    if (o["stage_one_prior"]) {  // since issue 52: a saved map's history
      try {
        e.history = readHistory(o["stage_one_prior"]);
      } catch (const std::exception& ex) {
        throw std::runtime_error("object " + std::to_string(e.id) + ": " + ex.what());
      }
    }
    objects.push_back(e);
  }
  return objects;
}

// The plane; its extent and evidence since issue 52 (without them a resumed estimator finds
// the plane again from its first keyframe).
SupportPlane readSupportPlane(const YAML::Node& sp) {
  SupportPlane p;
  p.valid = true;
  p.normal = yaml_io::parseVector3(sp["normal"]);
  p.height = sp["height"].as<double>();
  if (sp["centre"] && sp["axis_x"] && sp["size"]) {
    p.centre = yaml_io::parseVector3(sp["centre"]);
    p.size = Eigen::Vector2d(sp["size"][0].as<double>(), sp["size"][1].as<double>());
    const Eigen::Vector3d n = p.normal.normalized(),
                          x = yaml_io::parseVector3(sp["axis_x"]).normalized();
    p.axes.col(0) = x;
    p.axes.col(1) = n.cross(x);
    p.axes.col(2) = n;
    p.inliers = sp["inliers"].as<int>(0);
    p.observations = sp["observations"].as<int>(0);
  }
  if (!p.normal.allFinite() || !std::isfinite(p.height) || !p.centre.allFinite() ||
      !p.axes.allFinite() || !(p.normal.norm() > 0.5))
    throw std::runtime_error("final_map support_plane: not finite or no normal");
  return p;
}

StageTimings readTimings(const YAML::Node& t) {
  StageTimings s;
  s.consistency_ms = t["consistency"].as<double>();
  s.association_ms = t["association"].as<double>();
  if (t["lifecycle"]) s.lifecycle_ms = t["lifecycle"].as<double>();  // since issue 22
  s.stage_one_ms = t["stage_one"].as<double>();
  s.relations_ms = t["relations"].as<double>();
  s.stage_two_ms = t["stage_two"].as<double>();
  s.total_ms = t["total"].as<double>();
  return s;
}

}  // namespace

bool readRunResults(const std::string& path, const ModelSet& models, RunResults* results,
                    std::string* error) {
  try {
    const YAML::Node root = YAML::LoadFile(path);
    if (root["format"].as<std::string>("") != "geofusion_results_v1") {
      throw std::runtime_error("not a geofusion_results_v1 file");
    }
    RunResults r;
    r.method = root["method"].as<std::string>();
    r.source = root["source"].as<std::string>("");
    r.model_set = root["model_set"].as<std::string>("");
    if (root["config"]) r.config_yaml = YAML::Dump(root["config"]);
    r.recording_duration_s = root["recording_duration_s"].as<double>();
    r.wall_time_s = root["wall_time_s"].as<double>();
    r.peak_rss_mb = root["peak_rss_mb"].as<double>(0.0);
    r.frames_seen = root["frames_seen"].as<int>();
    r.frames_skipped = root["frames_skipped"].as<int>();
    for (const auto& [key, counts] : {std::pair{"frames_dropped", &r.frames_dropped},
                                      std::pair{"detections_dropped", &r.detections_dropped}}) {
      if (!root[key]) continue;
      for (const auto& kv : root[key])
        counts->emplace_back(kv.first.as<std::string>(), kv.second.as<std::size_t>());
    }
    r.keyframes_over_budget = root["keyframes_over_budget"].as<int>(0);
    if (const YAML::Node b = root["background"]) {
      r.has_background = true;
      r.background.submitted = b["keyframes_submitted"].as<std::size_t>(0);
      r.background.inserted = b["keyframes_inserted"].as<std::size_t>(0);
      r.background.skipped = b["keyframes_skipped"].as<std::size_t>(0);
      r.background.still = b["keyframes_still"].as<std::size_t>(0);
      r.background.p50_ms = b["ms_p50"].as<double>(0.0);
      r.background.p95_ms = b["ms_p95"].as<double>(0.0);
      r.background.max_ms = b["ms_max"].as<double>(0.0);
      r.background.total_ms = b["ms_total"].as<double>(0.0);
    }
    for (const YAML::Node& k : root["keyframes"]) {
      KeyframeResult kr;
      kr.keyframe = k["index"].as<int>();
      kr.stamp_s = k["stamp"].as<double>();
      kr.T_map_cam = yaml_io::parsePose(k["map_camera"], "map_camera");
      kr.timings = readTimings(k["timings_ms"]);
      readStages(k["stages"], &kr);
      kr.removed_ids = k["removed_ids"].as<std::vector<int>>();
      kr.removals = readRemovals(k["removals"]);
      kr.relocalisation = readRelocalisation(k["relocalisation"]);
      kr.skipped_detections = k["skipped_detections"].as<int>(0);
      kr.detections = readDetections(k["detections"]);
      kr.detection_warning = k["detection_warning"].as<std::string>("");
      kr.objects = readObjects(k["objects"], models);
      r.keyframes.push_back(std::move(kr));
    }
    const YAML::Node fm = root["final_map"];
    r.final_map.timings = readTimings(fm["timings_ms"]);
    readStages(fm["stages"], &r.final_map);
    r.final_map.objects = readObjects(fm["objects"], models);
    if (!r.keyframes.empty()) r.final_map.T_map_cam = r.keyframes.back().T_map_cam;
    auto index = [&](int id) {
      if (id == -1) return -1;
      for (std::size_t i = 0; i < r.final_map.objects.size(); ++i)
        if (r.final_map.objects[i].id == id) return static_cast<int>(i);
      throw std::runtime_error("contact refers to object " + std::to_string(id) +
                               ", which is not in the final map");
    };
    for (const YAML::Node& c : fm["contacts"]) {
      FeatureContact fc;
      fc.object_a = index(c["a"].as<int>());
      fc.object_b = index(c["b"].as<int>());
      fc.type = contactTypeOfShortName(c["type"].as<std::string>());
      fc.kind = contactKindOfName(c["kind"].as<std::string>());
      fc.distance_residual = c["distance_residual"].as<double>();
      // Files before the normal was written: none, so the support graph asks the heights.
      fc.normal = c["normal"] ? yaml_io::parseVector3(c["normal"]) : Eigen::Vector3d::Zero();
      r.final_map.contacts.push_back(fc);
    }
    if (const YAML::Node sp = fm["support_plane"]) r.support_plane = readSupportPlane(sp);
    for (const YAML::Node& t : root["trajectory"]) {
      r.trajectory_stamps.push_back(t["stamp"].as<double>());
      r.trajectory.push_back(yaml_io::parsePose(t["map_camera"], "trajectory map_camera"));
    }
    if (const YAML::Node m = root["map"]) {
      r.map_id = m["id"].as<std::string>();
      r.session = m["session"].as<std::string>("");
      r.keyframes_total = m["keyframes_total"].as<int>(0);
      r.next_object_id = m["next_object_id"].as<int>(0);
      r.T_map_odom = yaml_io::parsePose(m["map_odom"], "map map_odom");
      r.background_file = m["background"]["file"].as<std::string>("");
      r.background_bytes = m["background"]["bytes"].as<std::uint64_t>(0);
      r.background_checksum = m["background"]["fnv1a64"].as<std::string>("");
    }
    *results = std::move(r);
    return true;
  } catch (const std::exception& e) {
    if (error) *error = path + ": " + e.what();
    return false;
  }
}

}  // namespace geofusion
