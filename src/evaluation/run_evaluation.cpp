#include "geofusion/evaluation/run_evaluation.h"

#include "geofusion/evaluation/trajectory_metrics.h"
#include "geofusion/evaluation/vsd.h"

#include "geofusion/common/atomic_file.h"
#include "geofusion/config/config.h"
#include "geofusion/estimation/map_stability.h"
#include "geofusion/estimation/relations.h"
#include "geofusion/evaluation/bop_metrics.h"
#include "geofusion/evaluation/evaluation.h"
#include "geofusion/evaluation/keyframe_matcher.h"
#include "geofusion/evaluation/metrics.h"
#include "geofusion/physics/stability.h"
#include "geofusion/render/renderer.h"
#include "geofusion/simulation/clutter_scene.h"

#include <yaml-cpp/yaml.h>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <tuple>

namespace geofusion {

namespace {

// A plane n . x = h.
struct Plane {
  Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
  double h = 0.0;
};

// Heights of the object's lowest and highest hull vertices above the plane (negative: below).
std::pair<double, double> heightsAbove(const ObjectModel& model, const Eigen::Isometry3d& T,
                                       const Plane& plane) {
  return hullHeightsAbove(model, T, plane.n, plane.h);
}

double lowestAbove(const ObjectModel& model, const Eigen::Isometry3d& T, const Plane& plane) {
  return heightsAbove(model, T, plane).first;
}

double boundingRadius(const ObjectModel& model) {
  double r = 0.0;
  for (const auto& v : model.mesh.vertices) r = std::max(r, static_cast<double>(v.norm()));
  return r;
}

using ContactKey = std::tuple<int, int, std::string>;  // lower index, higher index, type

ContactKey keyOf(int a, int b, const std::string& type) {
  return {std::min(a, b), std::max(a, b), type};
}

// The run's header figures and the COCO categories (classes of the truth and of the estimates).
void describeRun(const GroundTruth& gt, const RunResults& results, RunEvaluation* ev) {
  ev->scene = gt.scene_name;
  ev->method = results.method;
  ev->config_yaml = results.config_yaml;
  ev->image_width = gt.intrinsics.width;
  ev->image_height = gt.intrinsics.height;
  std::set<std::pair<int, std::string>> classes;
  for (const SceneObject& o : gt.scene.objects) classes.insert({o.model->id, o.model->name});
  for (const KeyframeResult& k : results.keyframes)
    for (const ObjectEstimate& o : k.objects) classes.insert({o.model->id, o.model->name});
  ev->categories.assign(classes.begin(), classes.end());
  ev->recording_duration_s = results.recording_duration_s;
  ev->wall_time_s = results.wall_time_s;
  ev->peak_rss_mb = results.peak_rss_mb;
}

// One keyframe's images for COCO: the true objects' projected boxes (crowd when mostly hidden) and
// the estimate's boxes, each with its ADD-S against the same-class truths its box overlaps.
// BOP's view of each true object's model (bop_metrics.h), made once per class, and the VSD
// scorer with its test image (the true scene of the keyframe, rendered).
class BopModels {
 public:
  explicit BopModels(const EvaluationConfig& config, RunEvaluation* ev) {
    if (!config.vsd) return;
    auto renderer = std::make_shared<OffscreenRenderer>();
    if (renderer->ok())
      vsd_ = std::make_unique<VsdScorer>(renderer);
    else
      ev->warnings.push_back("VSD not computed: no OSMesa context (" + renderer->error() + ")");
  }
  const BopModel& of(const ObjectModel& model, RunEvaluation* ev) {
    auto it = models_.find(model.name);
    if (it == models_.end()) {
      it = models_.emplace(model.name, bopModelOf(model)).first;
      ev->diameters_m[model.id] = it->second.diameter_m;
    }
    return it->second;
  }
  /// The keyframe whose test depth vsd() uses, rendered on its first use.
  void setFrame(const GroundTruthFrame* f) {
    frame_ = f;
    rendered_ = scene_ok_ = false;
  }
  /// VSD errors (one per tau) of `model` at T_est against T_true in the frame's camera.
  std::vector<double> vsd(const GroundTruth& gt, const ObjectModel& model,
                          const Eigen::Isometry3d& T_est, const Eigen::Isometry3d& T_true,
                          double diameter_m) {
    if (!vsd_ || !frame_) return {};
    if (!rendered_) renderScene(gt, *frame_);
    return scene_ok_ ? vsd_->errors(model, T_est, T_true, diameter_m) : std::vector<double>{};
  }

 private:
  /// The keyframe's test depth: its present true objects (and the table of a generated scene)
  /// seen from the true camera.
  void renderScene(const GroundTruth& gt, const GroundTruthFrame& f) {
    rendered_ = true;
    if (!table_) table_ = std::make_unique<ObjectModel>(gt.scene.table.model());
    const Eigen::Isometry3d T_cam_map = f.T_map_optical.inverse();
    std::vector<PosedObject> scene;
    if (gt.platform == "robot") scene.push_back({table_.get(), T_cam_map * gt.scene.table.pose()});
    for (const SceneObject& o : gt.scene.objects)
      if (o.presentAt(f.index)) scene.push_back({o.model.get(), T_cam_map * o.T_world_obj});
    scene_ok_ = vsd_->setScene(gt.intrinsics, scene);
  }

  std::map<std::string, BopModel> models_;
  std::unique_ptr<VsdScorer> vsd_;
  std::unique_ptr<ObjectModel> table_;
  const GroundTruthFrame* frame_ = nullptr;
  bool rendered_ = false, scene_ok_ = false;
};

// The estimate's ADD-S and ADD against the image's ground truth (from `first_truth` on) whose
// boxes overlap its box.
void scoreEstimate(std::size_t first_truth, const std::vector<Eigen::Isometry3d>& truth_poses,
                   const ObjectEstimate& o, const Eigen::Isometry3d& T,
                   const EvaluationConfig& config, AddsEvaluator* adds, RunEvaluation* ev,
                   DetectionBox* d) {
  for (std::size_t g = first_truth; g < ev->ground_truth.size(); ++g) {
    const GroundTruthBox& t = ev->ground_truth[g];
    if (t.crowd || t.class_id != d->class_id || boxIou(t.box, d->box) < config.adds_min_iou)
      continue;
    const Eigen::Isometry3d& T_true = truth_poses[g - first_truth];
    d->adds_m.emplace_back(t.id, (*adds)(o.model->points, T, T_true));
    d->add_m.emplace_back(t.id, addError(o.model->points, T, T_true));
  }
}

// BOP's errors of the image's estimates (detections from `first_detection` on, at poses
// `T_est`) against every same-class truth not ignored: only for the estimates BOP's ViVo task
// scores, each class's highest-scored as many as it has targets in the image (ties in the order
// given, as bench_report.py's stable sort).
void scoreBop(const GroundTruth& gt, std::size_t first_truth, std::size_t first_detection,
              const std::vector<Eigen::Isometry3d>& truth_poses,
              const std::vector<Eigen::Isometry3d>& T_est, BopModels* bop, RunEvaluation* ev) {
  std::map<int, std::vector<std::size_t>> by_class;  // class -> its truths not ignored
  for (std::size_t g = first_truth; g < ev->ground_truth.size(); ++g)
    if (!ev->ground_truth[g].crowd) by_class[ev->ground_truth[g].class_id].push_back(g);
  std::vector<std::size_t> order;
  for (std::size_t i = first_detection; i < ev->detections.size(); ++i) order.push_back(i);
  std::stable_sort(order.begin(), order.end(), [ev](std::size_t a, std::size_t b) {
    return ev->detections[a].score > ev->detections[b].score;
  });
  std::map<int, std::size_t> scored;  // class -> estimates scored
  for (std::size_t i : order) {
    DetectionBox& d = ev->detections[i];
    const auto truths = by_class.find(d.class_id);
    if (truths == by_class.end() || scored[d.class_id]++ >= truths->second.size()) continue;
    const Eigen::Isometry3d& T = T_est[i - first_detection];
    for (std::size_t g : truths->second) {
      const GroundTruthBox& t = ev->ground_truth[g];
      const Eigen::Isometry3d& T_true = truth_poses[g - first_truth];
      const ObjectModel& model = *gt.scene.objects[static_cast<std::size_t>(t.object)].model;
      const BopModel& m = bop->of(model, ev);
      d.bop.push_back({t.id, mssdError(m, T, T_true), mspdError(m, T, T_true, gt.intrinsics),
                       bop->vsd(gt, model, T, T_true, m.diameter_m)});
    }
  }
}

void evaluateKeyframe(const GroundTruth& gt, const GroundTruthFrame& f, const KeyframeResult& k,
                      const EvaluationConfig& config, AddsEvaluator* adds, BopModels* bop,
                      RunEvaluation* ev) {
  const PinholeIntrinsics& K = gt.intrinsics;
  const int n_objects = static_cast<int>(gt.scene.objects.size());
  ev->images.emplace_back(k.keyframe, k.stamp_s);
  ev->timings.push_back(k.timings);
  const Eigen::Isometry3d T_cam_map_true = f.T_map_optical.inverse();
  const std::size_t first_truth = ev->ground_truth.size();
  std::vector<Eigen::Isometry3d> truth_poses;
  for (int i = 0; i < n_objects; ++i) {
    const SceneObject& o = gt.scene.objects[static_cast<std::size_t>(i)];
    if (!o.presentAt(f.index)) continue;  // taken away or not there yet (a changed scene)
    const Eigen::Isometry3d T = T_cam_map_true * o.T_world_obj;
    const Box2d box = projectedBox(o.model->points, T, K);
    if (box.empty()) continue;
    GroundTruthBox g;
    g.id = static_cast<int>(ev->ground_truth.size()) + 1;
    g.image = k.keyframe;
    g.class_id = o.model->id;
    g.box = box;
    g.object = i;
    g.visible_fraction = f.visible_fraction[static_cast<std::size_t>(i)];
    g.crowd = g.visible_fraction < config.min_visible_fraction;
    if (static_cast<int>(f.visible_boxes.size()) == n_objects) {
      const PixelBox& m = f.visible_boxes[static_cast<std::size_t>(i)];
      if (m.valid())
        g.mask_box = Box2d{double(m.x), double(m.y), double(m.x + m.width), double(m.y + m.height)};
    }
    ev->ground_truth.push_back(g);
    truth_poses.push_back(T);
  }
  const Eigen::Isometry3d T_cam_map = k.T_map_cam.inverse();
  const std::size_t first_detection = ev->detections.size();
  std::vector<Eigen::Isometry3d> T_est;
  bop->setFrame(&f);
  for (const ObjectEstimate& o : k.objects) {
    const Eigen::Isometry3d T = T_cam_map * o.T_map_obj;
    const Box2d box = projectedBox(o.model->points, T, K);
    if (box.empty()) continue;
    DetectionBox d;
    d.id = static_cast<int>(ev->detections.size()) + 1;
    d.image = k.keyframe;
    d.class_id = o.model->id;
    d.box = box;
    d.score = o.existence;
    d.object_id = o.id;
    scoreEstimate(first_truth, truth_poses, o, T, config, adds, ev, &d);
    ev->detections.push_back(std::move(d));
    T_est.push_back(T);
  }
  scoreBop(gt, first_truth, first_detection, truth_poses, T_est, bop, ev);
}

// The estimated map frame aligned to the true one by the trajectories (Umeyama); the residual is
// the method's ATE. The odometry it was given (the recorded odom -> base chain, the camera mounted
// as in the truth), aligned the same way at the same stamps, gives the ATE it started from.
void alignMapFrame(const RunResults& results, const KeyframeMatcher& frames, RunEvaluation* ev) {
  std::vector<Eigen::Vector3d> est_positions, true_positions, odometry_positions;
  for (std::size_t i = 0; i < results.trajectory.size(); ++i) {
    const GroundTruthFrame* f =
        i < results.trajectory_stamps.size() ? frames.at(results.trajectory_stamps[i]) : nullptr;
    if (!f) continue;
    est_positions.push_back(results.trajectory[i].translation());
    true_positions.push_back(f->T_map_optical.translation());
    odometry_positions.push_back(
        (f->T_odom_base * f->T_map_base.inverse() * f->T_map_optical).translation());
  }
  ev->T_true_est = alignTrajectories(est_positions, true_positions, &ev->alignment_rmse_m);
  alignTrajectories(odometry_positions, true_positions, &ev->odometry_ate_rmse_m);
}

// The final map, aligned, matched to the true objects by ADD-S.
MapScore evaluateFinalMap(const GroundTruth& gt, const std::vector<ObjectEstimate>& map,
                          const EvaluationConfig& config, RunEvaluation* ev) {
  std::vector<ObjectEstimate> aligned = map;
  for (ObjectEstimate& o : aligned) o.T_map_obj = ev->T_true_est * o.T_map_obj;
  const MapScore score = scoreMap(gt.scene, aligned, config.match_max_adds_m);
  const int n_objects = static_cast<int>(gt.scene.objects.size());
  ev->map_objects = static_cast<int>(map.size());
  ev->map_matched = score.true_positives;
  ev->true_objects = 0;  // those there at the end
  ev->map_adds_m = score.adds_m;
  for (int i = 0; i < n_objects; ++i) {
    const SceneObject& o = gt.scene.objects[static_cast<std::size_t>(i)];
    if (!o.presentAtTheEnd()) continue;
    ++ev->true_objects;
    ev->graph_true_objects.push_back({i, o.model->name, o.T_world_obj.translation(), -1});
  }
  for (std::size_t j = 0; j < aligned.size(); ++j) {
    ev->graph_estimated_objects.push_back({aligned[j].id, aligned[j].model->name,
                                           aligned[j].T_map_obj.translation(), score.match[j]});
  }
  return score;
}

// The final map is scored against the scene as it is at the end (a changed scene: without the
// objects taken away).
bool bothThereAtTheEnd(const ClutterScene& scene, const FeatureContact& c) {
  auto there = [&](int i) {
    return i < 0 || scene.objects[static_cast<std::size_t>(i)].presentAtTheEnd();
  };
  return there(c.object_a) && there(c.object_b);
}

// Every contact of the final map against the truth, per kind, as (object pair, kind) with the
// table as -1: an estimated contact is correct when both its objects matched and the truth has
// the pair in contact with that kind. The graphs of the evaluation file list them all.
void evaluateContactKinds(const GroundTruth& gt, const RunResults& results,
                          const std::function<int(int)>& truthOf,
                          const std::function<int(int)>& idOf, RunEvaluation* ev) {
  std::set<ContactKey> truth, seen;
  for (const FeatureContact& c : gt.scene.contacts) {
    if (!bothThereAtTheEnd(gt.scene, c)) continue;
    const ContactKey key = keyOf(c.object_a, c.object_b, toString(c.kind));
    if (!truth.insert(key).second) continue;
    ++ev->contacts_by_kind[static_cast<int>(c.kind)].truth;
    ev->graph_true_contacts.push_back(
        {c.object_a, c.object_b, shortName(c.type), toString(c.kind), true});
  }
  for (const FeatureContact& c : results.final_map.contacts) {
    const int a = truthOf(c.object_a), b = truthOf(c.object_b);
    const bool matched = (c.object_a < 0 || a >= 0) && (c.object_b < 0 || b >= 0);
    const ContactKey key =
        matched ? keyOf(a, b, toString(c.kind))
                : keyOf(-2 - idOf(c.object_a), -2 - idOf(c.object_b), toString(c.kind));
    if (!seen.insert(key).second) continue;
    const bool correct = matched && truth.count(key);
    ContactCounts& counts = ev->contacts_by_kind[static_cast<int>(c.kind)];
    ++counts.estimated;
    counts.correct += correct;
    ev->graph_estimated_contacts.push_back(
        {idOf(c.object_a), idOf(c.object_b), shortName(c.type), toString(c.kind), correct});
  }
}

// Contact graphs: support contacts, as (object pair, type) with the table as -1; an estimated
// contact is correct when both its objects matched and the truth has it.
void evaluateContactGraph(const GroundTruth& gt, const RunResults& results, const MapScore& score,
                          RunEvaluation* ev) {
  const std::vector<ObjectEstimate>& map = results.final_map.objects;
  std::set<ContactKey> true_keys;
  std::set<std::pair<int, int>> true_pairs, estimated_pairs;
  auto pairOf = [](const ContactKey& k) { return std::make_pair(std::get<0>(k), std::get<1>(k)); };
  std::set<int> matched_truth(score.match.begin(), score.match.end());
  matched_truth.insert(-1);
  for (const FeatureContact& c : gt.scene.contacts) {
    if (!c.support() || !bothThereAtTheEnd(gt.scene, c)) continue;
    const ContactKey key = keyOf(c.object_a, c.object_b, shortName(c.type));
    true_pairs.insert(pairOf(key));
    if (!true_keys.insert(key).second) continue;
    ev->true_contacts_between_matched +=
        matched_truth.count(c.object_a) && matched_truth.count(c.object_b);
  }
  ev->true_contacts = static_cast<int>(true_keys.size());
  ev->true_contact_pairs = static_cast<int>(true_pairs.size());
  ev->has_contacts = results.method == toString(Method::kGeoFusion);
  if (!ev->has_contacts) return;
  if (true_keys.empty()) {
    ev->warnings.push_back(
        "the ground truth has no support contact between objects present at the end (a file "
        "written before contacts were recorded, or a scene where nothing touches): contact "
        "precision, recall and F1 are undefined and reported as 0");
  }
  std::set<ContactKey> seen;
  const std::function<int(int)> truthOf = [&](int index) {
    return index < 0 ? -1 : score.match[static_cast<std::size_t>(index)];
  };
  const std::function<int(int)> idOf = [&](int index) {
    return index < 0 ? -1 : map[static_cast<std::size_t>(index)].id;
  };
  evaluateContactKinds(gt, results, truthOf, idOf, ev);
  for (const FeatureContact& c : results.final_map.contacts) {
    if (!c.support()) continue;
    const int a = truthOf(c.object_a), b = truthOf(c.object_b);
    const bool matched = (c.object_a < 0 || a >= 0) && (c.object_b < 0 || b >= 0);
    // Contacts of unmatched objects are wrong; duplicates (two features) count once.
    const ContactKey key =
        matched ? keyOf(a, b, shortName(c.type))
                : keyOf(-2 - idOf(c.object_a), -2 - idOf(c.object_b), shortName(c.type));
    if (estimated_pairs.insert(pairOf(key)).second)
      ev->correct_contact_pairs += matched && true_pairs.count(pairOf(key));
    if (!seen.insert(key).second) continue;
    ev->correct_contacts += matched && true_keys.count(key);
  }
  ev->estimated_contacts = static_cast<int>(seen.size());
  ev->estimated_contact_pairs = static_cast<int>(estimated_pairs.size());
}

// Keyframes in which the detector reported each persistent phantom (detection_truth -2 - k) and
// each object as a look-alike.
void countDetectorErrors(const GroundTruth& gt, std::vector<int>* phantom_keyframes,
                         std::vector<int>* swap_keyframes) {
  phantom_keyframes->assign(gt.phantoms.size(), 0);
  swap_keyframes->assign(gt.scene.objects.size(), 0);
  for (const GroundTruthFrame& f : gt.frames) {
    std::set<int> phantoms(f.detection_truth.begin(), f.detection_truth.end());
    for (int t : phantoms) {
      const int k = -2 - t;
      if (k >= 0 && k < static_cast<int>(phantom_keyframes->size()))
        ++(*phantom_keyframes)[static_cast<std::size_t>(k)];
    }
    for (int i : std::set<int>(f.swapped.begin(), f.swapped.end()))
      if (i >= 0 && i < static_cast<int>(swap_keyframes->size()))
        ++(*swap_keyframes)[static_cast<std::size_t>(i)];
  }
}

// An unmatched estimate of the final map (aligned) within `radius` of `position` whose class is
// (or, with `other_class`, is not) `class_name`.
bool unmatchedEstimateNear(const std::vector<ObjectEstimate>& map, const MapScore& score,
                           const Eigen::Isometry3d& T_true_est, const Eigen::Vector3d& position,
                           const std::string& class_name, bool other_class, double radius) {
  for (std::size_t j = 0; j < map.size(); ++j) {
    if (score.match[j] >= 0 || (map[j].model->name == class_name) == other_class) continue;
    if ((T_true_est * map[j].T_map_obj.translation() - position).norm() < radius) return true;
  }
  return false;
}

// The detector's persistent false objects and wrong classes, and which of them the final map
// keeps: a phantom as an unmatched object of its class at its place, a swap as an unmatched
// object of another class at the swapped object's place.
void evaluateDetectorErrors(const GroundTruth& gt, const std::vector<ObjectEstimate>& map,
                            const MapScore& score, const EvaluationConfig& config,
                            RunEvaluation* ev) {
  std::vector<int> phantom_keyframes, swap_keyframes;
  countDetectorErrors(gt, &phantom_keyframes, &swap_keyframes);
  for (std::size_t k = 0; k < gt.phantoms.size(); ++k) {
    if (phantom_keyframes[k] < config.persistent_min_keyframes) continue;
    ++ev->persistent_phantoms;
    const PhantomObject& p = gt.phantoms[k];
    ev->surviving_phantoms +=
        unmatchedEstimateNear(map, score, ev->T_true_est, p.T_world_obj.translation(), p.class_name,
                              false, config.phantom_match_m);
  }
  for (std::size_t i = 0; i < gt.scene.objects.size(); ++i) {
    if (swap_keyframes[i] < config.persistent_min_keyframes) continue;
    ++ev->persistent_swaps;
    const SceneObject& o = gt.scene.objects[i];
    ev->surviving_swaps +=
        unmatchedEstimateNear(map, score, ev->T_true_est, o.T_world_obj.translation(),
                              o.model->name, true, config.lifecycle_match_m);
  }
}

// The table in the estimate's own frame: the method's own support plane when it has one, else the
// true table brought into the estimate's frame.
Plane tableOf(const GroundTruth& gt, const RunResults& results, const RunEvaluation& ev) {
  Plane table;
  if (results.support_plane.valid) {
    table.n = results.support_plane.normal.normalized();
    table.h = results.support_plane.height;
  } else {
    const Eigen::Isometry3d T_est_true = ev.T_true_est.inverse();
    table.n = T_est_true.linear() * Eigen::Vector3d::UnitZ();
    table.h = table.n.dot(T_est_true * Eigen::Vector3d(0, 0, gt.scene.table.height_m));
  }
  return table;
}

// "class #id (true)" or "(false)" for map object i: how evaluate_run names an implausible pair.
std::string describeMapObject(const std::vector<ObjectEstimate>& map, const MapScore& score,
                              std::size_t i) {
  const bool matched = i < score.match.size() && score.match[i] >= 0;
  return map[i].model->name + " #" + std::to_string(map[i].id) + (matched ? " (true)" : " (false)");
}

// Appends `value` to `values`, and names the pair when it is the largest so far.
void recordPairValue(double value, const std::string& pair, std::vector<double>* values,
                     std::string* largest_pair) {
  if (values->empty() || value > *std::max_element(values->begin(), values->end()))
    *largest_pair = pair;
  values->push_back(value);
}

// Physical plausibility in the estimate's own frame: interpenetration of touching pairs and of
// objects with the table, and the gaps of the true support contacts between matched objects.
void evaluatePlausibility(const GroundTruth& gt, const RunResults& results, const MapScore& score,
                          const EvaluationConfig& config, RunEvaluation* ev) {
  const std::vector<ObjectEstimate>& map = results.final_map.objects;
  const Plane table = tableOf(gt, results, *ev);
  HullCollider collider;
  std::vector<double> radius;
  for (const ObjectEstimate& o : map) radius.push_back(boundingRadius(*o.model));
  for (std::size_t i = 0; i < map.size(); ++i) {
    // Into the table: an object that reaches through its top surface. One wholly below it (a
    // stray estimate on the floor) does not interpenetrate the table; it is a false object.
    const auto [low, high] = heightsAbove(*map[i].model, map[i].T_map_obj, table);
    if (low < config.touch_distance_m && high > 0.0)
      recordPairValue(std::max(0.0, -low), "table / " + describeMapObject(map, score, i),
                      &ev->penetration_m, &ev->deepest_pair);
    for (std::size_t j = i + 1; j < map.size(); ++j) {
      const double centres =
          (map[i].T_map_obj.translation() - map[j].T_map_obj.translation()).norm();
      if (centres > radius[i] + radius[j] + config.touch_distance_m) continue;
      const double depth =
          collider.penetration(map[i].model, map[i].T_map_obj, map[j].model, map[j].T_map_obj);
      if (depth > 0.0 || collider.distance(map[i].model, map[i].T_map_obj, map[j].model,
                                           map[j].T_map_obj) < config.touch_distance_m)
        recordPairValue(depth,
                        describeMapObject(map, score, i) + " / " + describeMapObject(map, score, j),
                        &ev->penetration_m, &ev->deepest_pair);
    }
  }
  std::map<int, std::size_t> estimate_of;  // true index -> map index
  for (std::size_t j = 0; j < score.match.size(); ++j)
    if (score.match[j] >= 0) estimate_of[score.match[j]] = j;
  for (const GraphContact& c : ev->graph_true_contacts) {
    if (!estimate_of.count(c.b) || (c.a >= 0 && !estimate_of.count(c.a))) continue;
    const ObjectEstimate& b = map[estimate_of[c.b]];
    const std::string b_name = describeMapObject(map, score, estimate_of[c.b]);
    if (c.a < 0) {
      recordPairValue(std::max(0.0, lowestAbove(*b.model, b.T_map_obj, table)), "table / " + b_name,
                      &ev->gap_m, &ev->widest_gap_pair);
    } else {
      const ObjectEstimate& a = map[estimate_of[c.a]];
      recordPairValue(collider.distance(a.model, a.T_map_obj, b.model, b.T_map_obj),
                      describeMapObject(map, score, estimate_of[c.a]) + " / " + b_name, &ev->gap_m,
                      &ev->widest_gap_pair);
    }
  }
}

// How high the map's objects on the table stand above it, against their true poses brought into
// the map's frame (the real frames' lift, issue 50).
void evaluateTableClearance(const GroundTruth& gt, const RunResults& results, const MapScore& score,
                            RunEvaluation* ev) {
  const std::vector<ObjectEstimate>& map = results.final_map.objects;
  const Plane table = tableOf(gt, results, *ev);
  const Eigen::Isometry3d T_est_true = ev->T_true_est.inverse();
  constexpr double kOnTheTable = 0.02;
  for (std::size_t i = 0; i < map.size() && i < score.match.size(); ++i) {
    if (score.match[i] < 0) continue;
    const SceneObject& truth = gt.scene.objects[static_cast<std::size_t>(score.match[i])];
    TableClearance c;
    c.object = describeMapObject(map, score, i);
    c.truth_m = lowestAbove(*truth.model, T_est_true * truth.T_world_obj, table);
    c.estimate_m = lowestAbove(*map[i].model, map[i].T_map_obj, table);
    if (std::min(std::abs(c.truth_m), std::abs(c.estimate_m)) < kOnTheTable)
      ev->table_clearance.push_back(c);
  }
}

// The run's configuration, for its `physics` and `scene_graph` settings (the defaults when the
// results carry none or it does not load; a warning in `ev` says so).
GeoFusionConfig resultsConfig(const RunResults& results, RunEvaluation* ev) {
  GeoFusionConfig config;
  if (results.config_yaml.empty()) return config;
  ConfigReport report;
  if (!loadConfigText(results.config_yaml, "the results' configuration", &config, &report)) {
    ev->warnings.push_back("the results' configuration does not load (" +
                           (report.errors.empty() ? std::string("?") : report.errors.front()) +
                           "); the default physics and scene_graph settings are used");
    return GeoFusionConfig();
  }
  return config;
}

// "class #id (true)" for a body of the map's stability check, "table" for the plane.
std::string describeBody(const std::vector<ObjectEstimate>& map, const MapScore& score, int id) {
  if (id == physics::kPlaneId) return "table";
  for (std::size_t i = 0; i < map.size(); ++i)
    if (map[i].id == id) return describeMapObject(map, score, i);
  return "#" + std::to_string(id);
}

// Physical stability (issue 50): the final map on its support plane under gravity, and the true
// scene on the true table as the reference; the share of the true objects that stay put.
void evaluateStability(const GroundTruth& gt, const RunResults& results, const MapScore& score,
                       const physics::StabilityConfig& config, RunEvaluation* ev) {
  const std::vector<ObjectEstimate>& map = results.final_map.objects;
  ev->stability_config = config;
  const Plane table = tableOf(gt, results, *ev);
  SupportPlane plane;
  plane.valid = true;
  plane.normal = table.n;
  plane.height = table.h;
  ev->stability = checkMapStability(map, &plane, -table.n, ev->stability_config);
  for (std::size_t i = 0; i < map.size(); ++i) {
    if (i >= score.match.size() || score.match[i] < 0) continue;
    const physics::BodyMotion* m = ev->stability.find(map[i].id);
    ++ev->stability_true_objects;
    ev->stability_true_id[map[i].id] = score.match[i];
    ev->stability_true_stable += m && m->stable;
    ev->stability_true_interpenetrating += m && m->interpenetrating;
  }
  const auto& [a, b] = ev->stability.least_stable_pair;
  if (a != -1)
    ev->least_stable_pair = describeBody(map, score, a) + " / " + describeBody(map, score, b);
  for (const std::string& w : ev->stability.warnings) ev->warnings.push_back("stability: " + w);

  std::vector<physics::StabilityBody> truth;
  for (std::size_t i = 0; i < gt.scene.objects.size(); ++i)
    truth.push_back({int(i), gt.scene.objects[i].model, gt.scene.objects[i].T_world_obj});
  const physics::StabilityPlane true_table{Eigen::Vector3d::UnitZ(), gt.scene.table.height_m};
  ev->stability_truth =
      physics::checkStability(truth, &true_table, -Eigen::Vector3d::UnitZ(), ev->stability_config);
  ev->has_stability = true;
}

// The true scene's support graph at the end (objects taken away keep no relation).
SupportGraph trueSceneGraph(const GroundTruth& gt) {
  std::vector<SupportGraphObject> objects;
  for (std::size_t i = 0; i < gt.scene.objects.size(); ++i) {
    const SceneObject& o = gt.scene.objects[i];
    SupportGraphObject g;
    g.id = static_cast<int>(i);
    g.class_name = o.model->name;
    g.centre = o.T_world_obj * boxOf(*o.model).center().cast<double>();
    objects.push_back(std::move(g));
  }
  std::vector<FeatureContact> contacts;
  for (const FeatureContact& c : gt.scene.contacts)
    if (bothThereAtTheEnd(gt.scene, c)) contacts.push_back(c);
  return buildSupportGraph(objects, contacts, -Eigen::Vector3d::UnitZ());
}

// What taking true object `t` from the true objects not in `taken` does to the others under
// gravity: the largest growth of another object's motion against the scene with `t` still there
// ("moves 12.3 mm / 4.1 deg more: class #i"), and whether it is over the stability bounds.
bool disturbsInPhysics(const GroundTruth& gt, const std::set<int>& taken, int t,
                       const physics::StabilityConfig& config, std::string* what) {
  std::vector<physics::StabilityBody> with, without;
  for (std::size_t i = 0; i < gt.scene.objects.size(); ++i) {
    if (taken.count(static_cast<int>(i))) continue;
    const physics::StabilityBody body{static_cast<int>(i), gt.scene.objects[i].model,
                                      gt.scene.objects[i].T_world_obj};
    with.push_back(body);
    if (static_cast<int>(i) != t) without.push_back(body);
  }
  const physics::StabilityPlane table{Eigen::Vector3d::UnitZ(), gt.scene.table.height_m};
  const auto before = physics::checkStability(with, &table, -Eigen::Vector3d::UnitZ(), config);
  const auto after = physics::checkStability(without, &table, -Eigen::Vector3d::UnitZ(), config);
  double worst = 0.0, dt_worst = 0.0, dr_worst = 0.0;
  int moved = -1;
  for (const physics::BodyMotion& m : after.bodies) {
    const physics::BodyMotion* b = before.find(m.id);
    if (!b || !m.simulated || !b->simulated) continue;
    const double dt = m.translation_m - b->translation_m, dr = m.rotation_deg - b->rotation_deg;
    const double share =
        std::max(dt / config.stable_translation_m, dr / config.stable_rotation_deg);
    if (share > worst) worst = share, dt_worst = dt, dr_worst = dr, moved = m.id;
  }
  char line[160];
  std::snprintf(line, sizeof(line), "in physics the rest moves at most %.1f mm / %.1f deg more",
                1000 * dt_worst, dr_worst);
  *what = line;
  if (moved >= 0)
    *what += " (" + gt.scene.objects[static_cast<std::size_t>(moved)].model->name + " #" +
             std::to_string(moved) + ")";
  return worst > 1.0;
}

// The map's removal order against the true support graph (issue 50): each step that takes a true
// object is unsafe when a true object still there, which the map also has, rests or leans on it;
// "free to pick" against the truth's.
void evaluateSceneGraph(const GroundTruth& gt, const RunResults& results, const MapScore& score,
                        const SupportGraphConfig& config, RunEvaluation* ev) {
  const std::vector<ObjectEstimate>& map = results.final_map.objects;
  const Plane table = tableOf(gt, results, *ev);
  ev->scene_graph = mapSupportGraph(map, results.final_map.contacts, -table.n,
                                    ev->has_stability ? &ev->stability : nullptr, config);
  const SupportGraph truth = trueSceneGraph(gt);
  std::map<int, int> truth_of_id;  // map id -> true index
  for (std::size_t i = 0; i < map.size() && i < score.match.size(); ++i)
    if (score.match[i] >= 0) truth_of_id[map[i].id] = score.match[i];
  std::set<int> in_map, taken;
  for (const auto& [id, t] : truth_of_id) in_map.insert(t);
  for (int id : ev->scene_graph.removal_order) {
    const auto it = truth_of_id.find(id);
    if (it == truth_of_id.end()) continue;  // a false object: nothing true is moved
    const SupportGraphNode& node = truth.nodes[static_cast<std::size_t>(it->second)];
    int above_in_map = -1;
    bool above_missed = false;
    for (const std::vector<int>* on : {&node.supports, &node.leaned_on_by})
      for (int above : *on) {
        if (taken.count(above)) continue;
        if (in_map.count(above))
          above_in_map = above;
        else
          above_missed = true;
      }
    ++ev->plan_steps;
    ev->plan_unsafe_steps += above_in_map >= 0;
    ev->plan_steps_under_missed += above_in_map < 0 && above_missed;
    if (above_in_map >= 0) {
      const std::string step = "took " + supportGraphName(ev->scene_graph, id) + " (true) before " +
                               supportGraphName(truth, above_in_map) +
                               " (true) resting or leaning on it";
      if (ev->first_unsafe_step.empty()) ev->first_unsafe_step = step;
      std::string physics;
      const bool disturbs =
          disturbsInPhysics(gt, taken, it->second, ev->stability_config, &physics);
      ev->plan_unsafe_steps_in_physics += disturbs;
      ev->unsafe_steps.push_back(step + ": " + physics + (disturbs ? "" : ", disturbs nothing"));
    }
    taken.insert(it->second);
    const SupportGraphNode* estimated = ev->scene_graph.find(id);
    ev->free_predicted += estimated && estimated->free_to_pick;
    ev->free_correct += estimated && estimated->free_to_pick && node.free_to_pick;
    ev->free_true += node.free_to_pick;
  }
  for (const std::string& w : ev->scene_graph.warnings) ev->warnings.push_back("scene graph: " + w);
  ev->has_scene_graph = true;
}

// Which true objects are in keyframe `k`'s map: an estimate of the class within the match
// distance, in the truth's frame (the final trajectory alignment).
std::vector<bool> mappedObjects(const GroundTruth& gt, const KeyframeResult& k,
                                const EvaluationConfig& config,
                                const Eigen::Isometry3d& T_true_est) {
  std::vector<bool> mapped(gt.scene.objects.size(), false);
  for (std::size_t i = 0; i < gt.scene.objects.size(); ++i) {
    const SceneObject& truth = gt.scene.objects[i];
    for (const ObjectEstimate& o : k.objects) {
      if (o.model->name != truth.model->name) continue;
      const Eigen::Vector3d p = T_true_est * o.T_map_obj.translation();
      if ((p - truth.T_world_obj.translation()).norm() < config.lifecycle_match_m) {
        mapped[i] = true;
        break;
      }
    }
  }
  return mapped;
}

// Whether the camera of a keyframe looks at where the object is (or was): its centre in front
// of the camera and inside the image.
bool inView(const SceneObject& o, const GroundTruthFrame& f, const PinholeIntrinsics& K) {
  const Eigen::Vector3d p = f.T_map_optical.inverse() * o.T_world_obj.translation();
  if (p.z() <= 0.05) return false;
  const double u = K.fx * p.x() / p.z() + K.cx, v = K.fy * p.y() / p.z() + K.cy;
  return u >= 0 && v >= 0 && u < K.width && v < K.height;
}

// Whether the camera of frame f sees where object i (taken away) stood: at least
// well_seen_min_visible of its old place unhidden (issue 32); files before that: its centre in
// the image.
bool placeSeen(const SceneObject& o, std::size_t i, const GroundTruthFrame& f,
               const PinholeIntrinsics& K, const EvaluationConfig& config) {
  if (f.place_visible_fraction.size() > i && f.place_visible_fraction[i] >= 0.0)
    return f.place_visible_fraction[i] >= config.well_seen_min_visible;
  return inView(o, f, K);
}

// Object lifecycle: for every true object, when it enters the online map, how often it leaves and
// comes back, and whether a well-seen object is lost. Not for FbF (no map that persists).
void evaluateLifecycle(const GroundTruth& gt, const RunResults& results,
                       const KeyframeMatcher& frames, const MapScore& score,
                       const EvaluationConfig& config, RunEvaluation* ev) {
  Method method = Method::kGeoFusion;
  ev->has_lifecycle =
      !(parseMethod(results.method, &method) && stagesOf(method).map_is_keyframe_detections);
  if (!ev->has_lifecycle) return;
  const std::size_t n = gt.scene.objects.size();
  std::vector<ObjectLifecycle> life(n);
  std::vector<int> absence(n, 0);
  std::vector<bool> was_mapped(n, false);
  int t = 0;
  for (const KeyframeResult& k : results.keyframes) {
    const GroundTruthFrame* f = frames.at(k.stamp_s);
    if (!f || f->visible_fraction.size() != n) continue;
    const std::vector<bool> mapped = mappedObjects(gt, k, config, ev->T_true_est);
    for (std::size_t i = 0; i < n; ++i) {
      ObjectLifecycle& l = life[i];
      l.object = static_cast<int>(i);
      if (f->visible_fraction[i] >= config.well_seen_min_visible) ++l.well_seen_keyframes;
      const SceneObject& o = gt.scene.objects[i];
      if (l.removed_keyframe < 0 && !o.presentAtTheEnd() && f->index >= o.present_until_frame &&
          placeSeen(o, i, *f, gt.intrinsics, config))
        l.removed_keyframe = t;
      if (mapped[i]) {
        l.last_mapped = t;
        if (l.first_mapped < 0) l.first_mapped = t;
        if (!was_mapped[i] && absence[i] > 0) ++l.returns;
        absence[i] = 0;
      } else if (l.first_mapped >= 0) {
        if (was_mapped[i]) ++l.departures;
        l.longest_absence = std::max(l.longest_absence, ++absence[i]);
      }
      was_mapped[i] = mapped[i];
    }
    ++t;
  }
  for (int j : score.match)
    if (j >= 0) life[static_cast<std::size_t>(j)].in_final_map = true;
  for (ObjectLifecycle& l : life) {
    const SceneObject& o = gt.scene.objects[static_cast<std::size_t>(l.object)];
    if (!o.presentAtTheEnd()) {                         // taken away: how long the map kept it
      if (l.first_mapped < 0) l.removed_keyframe = -1;  // never mapped: nothing to let go
      l.ghost = l.removed_keyframe >= 0 && l.last_mapped == t - 1;
      if (l.removed_keyframe >= 0 && !l.ghost)
        l.removal_latency = std::max(0, l.last_mapped + 1 - l.removed_keyframe);
      continue;
    }
    l.lost = l.well_seen_keyframes >= config.well_seen_min_keyframes &&
             (!l.in_final_map || l.longest_absence > config.lost_absence_keyframes);
  }
  ev->lifecycle = std::move(life);
}

}  // namespace

bool evaluateRun(const GroundTruth& gt, const RunResults& results, const EvaluationConfig& config,
                 RunEvaluation* evaluation, std::string* error) {
  RunEvaluation ev;
  ev.evaluation_config = config;
  describeRun(gt, results, &ev);
  const KeyframeMatcher frames(gt, config.stamp_tolerance_s);
  AddsEvaluator adds;
  BopModels bop(config, &ev);
  for (const KeyframeResult& k : results.keyframes) {
    for (const DetectionReport& d : k.detections) {
      ev.class_changes += d.decision == DetectionDecision::kClassChanged;
      ev.classes_kept += d.decision == DetectionDecision::kClassKept;
    }
    const GroundTruthFrame* f = frames.at(k.stamp_s);
    if (!f || f->visible_fraction.size() != gt.scene.objects.size()) {
      ++ev.unmatched_keyframes;
      continue;
    }
    evaluateKeyframe(gt, *f, k, config, &adds, &bop, &ev);
  }
  if (ev.images.empty()) {
    if (error) *error = "no keyframe of the results is a keyframe of the ground truth";
    return false;
  }
  alignMapFrame(results, frames, &ev);
  ev.final_solve = results.final_map.timings;
  const MapScore score = evaluateFinalMap(gt, results.final_map.objects, config, &ev);
  evaluateContactGraph(gt, results, score, &ev);
  evaluateDetectorErrors(gt, results.final_map.objects, score, config, &ev);
  evaluatePlausibility(gt, results, score, config, &ev);
  evaluateTableClearance(gt, results, score, &ev);
  const GeoFusionConfig run_config = resultsConfig(results, &ev);  // once: it parses YAML
  evaluateStability(gt, results, score, run_config.estimator.physics, &ev);
  evaluateSceneGraph(gt, results, score, run_config.scene_graph, &ev);
  evaluateLifecycle(gt, results, frames, score, config, &ev);
  *evaluation = std::move(ev);
  return true;
}

namespace {

// One stability check as JSON: the counts, the bounds and every body's motion.
// `true_id`: the true object a map body matched (-1: none; absent for the truth's bodies).
nlohmann::json stabilityResultJson(const physics::StabilityResult& r,
                                   const std::map<int, int>* true_id = nullptr) {
  nlohmann::json bodies = nlohmann::json::array();
  for (const physics::BodyMotion& m : r.bodies) {
    bodies.push_back({{"id", m.id},
                      {"simulated", m.simulated},
                      {"problem", m.problem},
                      {"translation_mm", 1000 * m.translation_m},
                      {"rotation_deg", m.rotation_deg},
                      {"start_penetration_mm", 1000 * m.start_penetration_m},
                      {"penetrating_id", m.penetrating_id},
                      {"interpenetrating", m.interpenetrating},
                      {"stable", m.stable}});
    if (true_id) {
      const auto it = true_id->find(m.id);
      bodies.back()["true_id"] = it == true_id->end() ? -1 : it->second;
    }
  }
  return {{"has_plane", r.has_plane},
          {"simulated", r.simulated},
          {"interpenetrating", r.interpenetrating},
          {"checked", r.checked},
          {"stable", r.stable},
          {"mean_translation_mm", 1000 * r.mean_translation_m},
          {"max_translation_mm", 1000 * r.max_translation_m},
          {"max_rotation_deg", r.max_rotation_deg},
          {"least_stable_pair", {r.least_stable_pair.first, r.least_stable_pair.second}},
          {"least_stable_pair_mm", 1000 * r.least_stable_pair_m},
          {"bodies", bodies}};
}

// The plan's block: its removal order (map ids) and how it fares against the true support graph.
nlohmann::json sceneGraphJson(const RunEvaluation& e) {
  nlohmann::json free = {
      {"predicted", e.free_predicted}, {"correct", e.free_correct}, {"true", e.free_true}};
  free["precision"] = e.free_predicted > 0
                          ? nlohmann::json(double(e.free_correct) / e.free_predicted)
                          : nlohmann::json(nullptr);
  return {{"removal_order", e.scene_graph.removal_order},
          {"true_steps", e.plan_steps},
          {"unsafe_steps", e.plan_unsafe_steps},
          {"steps_under_missed_objects", e.plan_steps_under_missed},
          {"first_unsafe_step", e.first_unsafe_step},
          {"unsafe_steps_in_physics", e.plan_unsafe_steps_in_physics},
          {"unsafe_step_details", e.unsafe_steps},
          {"free_to_pick", free},
          {"warnings", e.scene_graph.warnings}};
}

// The stability block: the settings, the map's check, its true objects, the truth's check.
nlohmann::json stabilityJson(const RunEvaluation& e) {
  const physics::StabilityConfig& c = e.stability_config;
  nlohmann::json settings = {{"convex_parts", c.convex_parts}};
  for (const physics::StabilitySetting& s : physics::stabilitySettings())
    settings[s.key] = c.*s.field;
  return {{"settings", settings},
          {"true_objects", e.stability_true_objects},
          {"true_stable", e.stability_true_stable},
          {"true_interpenetrating", e.stability_true_interpenetrating},
          {"least_stable_pair", e.least_stable_pair},
          {"map", stabilityResultJson(e.stability, &e.stability_true_id)},
          {"ground_truth", stabilityResultJson(e.stability_truth)}};
}

// A YAML tree as JSON: maps and lists as they are, scalars as booleans, numbers or strings.
nlohmann::json jsonOf(const YAML::Node& n) {
  if (n.IsMap()) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& kv : n) j[kv.first.as<std::string>()] = jsonOf(kv.second);
    return j;
  }
  if (n.IsSequence()) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& v : n) j.push_back(jsonOf(v));
    return j;
  }
  if (!n.IsScalar()) return nullptr;
  bool b;
  double d;
  if (n.Tag() != "!" && YAML::convert<bool>::decode(n, b)) return b;
  if (n.Tag() != "!" && YAML::convert<double>::decode(n, d)) return d;
  return n.Scalar();
}

nlohmann::json boxJson(const Box2d& b) {
  return nlohmann::json::array({b.x0, b.y0, b.width(), b.height()});
}

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

double maxOf(const std::vector<double>& v) {
  return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
}

std::vector<double> scaled(const std::vector<double>& v, double k) {
  std::vector<double> out;
  for (double x : v) out.push_back(k * x);
  return out;
}

// The ground truth's boxes, COCO's annotations.
nlohmann::json annotationsJson(const RunEvaluation& e) {
  using nlohmann::json;
  json out = json::array();
  for (const GroundTruthBox& g : e.ground_truth) {
    out.push_back({{"id", g.id},
                   {"image_id", g.image},
                   {"category_id", g.class_id},
                   {"bbox", boxJson(g.box)},
                   {"area", g.box.width() * g.box.height()},
                   {"iscrowd", g.crowd ? 1 : 0},
                   {"mask_bbox", g.mask_box.empty() ? json(nullptr) : boxJson(g.mask_box)},
                   {"object", g.object},
                   {"visible_fraction", g.visible_fraction}});
  }
  return out;
}

nlohmann::json detectionsJson(const RunEvaluation& e) {
  using nlohmann::json;
  json out = json::array();
  for (const DetectionBox& d : e.detections) {
    json adds = json::object(), add = json::object(), mssd = json::object(), mspd = json::object(),
         vsd = json::object();
    for (const auto& a : d.adds_m) adds[std::to_string(a.first)] = a.second;
    for (const auto& a : d.add_m) add[std::to_string(a.first)] = a.second;
    for (const auto& b : d.bop) {
      mssd[std::to_string(b.truth)] = b.mssd_m;
      mspd[std::to_string(b.truth)] = std::isfinite(b.mspd_px) ? json(b.mspd_px) : json(nullptr);
      if (!b.vsd.empty()) vsd[std::to_string(b.truth)] = b.vsd;
    }
    out.push_back({{"id", d.id},
                   {"image_id", d.image},
                   {"category_id", d.class_id},
                   {"bbox", boxJson(d.box)},
                   {"score", d.score},
                   {"object_id", d.object_id},
                   {"adds_m", adds},
                   {"add_m", add},
                   {"mssd_m", mssd},
                   {"mspd_px", mspd}});
    if (e.evaluation_config.vsd) out.back()["vsd"] = vsd;  // per truth, one error per tau
  }
  return out;
}

// The contacts of the final map against the true ones, by kind (null when not evaluated).
nlohmann::json contactCountsJson(const RunEvaluation& e) {
  using nlohmann::json;
  json contacts = nullptr;
  if (e.has_contacts) {
    contacts = {{"true", e.true_contacts},
                {"estimated", e.estimated_contacts},
                {"correct", e.correct_contacts},
                {"true_between_matched", e.true_contacts_between_matched},
                {"true_pairs", e.true_contact_pairs},
                {"estimated_pairs", e.estimated_contact_pairs},
                {"correct_pairs", e.correct_contact_pairs}};
    for (ContactKind k : {ContactKind::kSupport, ContactKind::kLeaning, ContactKind::kSide}) {
      const ContactCounts& n = e.contacts_by_kind[static_cast<int>(k)];
      contacts["by_kind"][toString(k)] = {
          {"true", n.truth}, {"estimated", n.estimated}, {"correct", n.correct}};
    }
  }
  return contacts;
}

// Each true object's life in the map, and the totals (null when not evaluated).
nlohmann::json lifecycleJson(const RunEvaluation& e) {
  using nlohmann::json;
  json lifecycle = nullptr;
  if (e.has_lifecycle) {
    json objects = json::array();
    int lost = 0, returns = 0, removals = 0, ghosts = 0;
    json latencies = json::array();
    for (const ObjectLifecycle& l : e.lifecycle) {
      objects.push_back({{"object", l.object},
                         {"well_seen_keyframes", l.well_seen_keyframes},
                         {"first_mapped", l.first_mapped},
                         {"departures", l.departures},
                         {"returns", l.returns},
                         {"longest_absence", l.longest_absence},
                         {"in_final_map", l.in_final_map},
                         {"lost", l.lost},
                         {"removed_keyframe", l.removed_keyframe},
                         {"last_mapped", l.last_mapped},
                         {"removal_latency", l.removal_latency},
                         {"ghost", l.ghost}});
      lost += l.lost;
      returns += l.returns;
      removals += l.removed_keyframe >= 0;
      ghosts += l.ghost;
      if (l.removal_latency >= 0) latencies.push_back(l.removal_latency);
    }
    lifecycle = {{"objects", objects},   {"lost", lost},     {"flip_flops", returns},
                 {"removals", removals}, {"ghosts", ghosts}, {"removal_latencies", latencies}};
  }
  return lifecycle;
}

nlohmann::json evaluationConfigJson(const EvaluationConfig& c) {
  return {{"min_visible_fraction", c.min_visible_fraction},
          {"match_max_adds_m", c.match_max_adds_m},
          {"touch_distance_m", c.touch_distance_m},
          {"adds_min_iou", c.adds_min_iou},
          {"stamp_tolerance_s", c.stamp_tolerance_s},
          {"lifecycle_match_m", c.lifecycle_match_m},
          {"well_seen_min_keyframes", c.well_seen_min_keyframes},
          {"well_seen_min_visible", c.well_seen_min_visible},
          {"lost_absence_keyframes", c.lost_absence_keyframes},
          {"persistent_min_keyframes", c.persistent_min_keyframes},
          {"phantom_match_m", c.phantom_match_m},
          {"vsd", c.vsd}};
}

// Each stage's time, keyframe by keyframe.
nlohmann::json timingsJson(const std::vector<StageTimings>& keyframes) {
  nlohmann::json timings = nlohmann::json::object();
  auto series = [&](const char* name, double StageTimings::*field) {
    std::vector<double> v;
    for (const StageTimings& t : keyframes) v.push_back(t.*field);
    timings[name] = v;
  };
  series("consistency", &StageTimings::consistency_ms);
  series("association", &StageTimings::association_ms);
  series("lifecycle", &StageTimings::lifecycle_ms);
  series("stage_one", &StageTimings::stage_one_ms);
  series("relations", &StageTimings::relations_ms);
  series("stage_two", &StageTimings::stage_two_ms);
  series("total", &StageTimings::total_ms);
  return timings;
}

nlohmann::json graphObjectsJson(const std::vector<GraphObject>& list, bool estimated) {
  using nlohmann::json;
  json out = json::array();
  for (const GraphObject& o : list) {
    json x = {{estimated ? "id" : "index", o.id},
              {"class_name", o.class_name},
              {"xy", {o.position.x(), o.position.y()}},
              {"z", o.position.z()}};
    if (estimated) x["match"] = o.match;
    out.push_back(x);
  }
  return out;
}

nlohmann::json graphContactsJson(const std::vector<GraphContact>& list) {
  using nlohmann::json;
  json out = json::array();
  for (const GraphContact& c : list) {
    out.push_back({{"a", c.a},
                   {"b", c.b},
                   {"type", c.type},
                   {"kind", c.kind},
                   {"support", c.kind == "support"},
                   {"correct", c.correct}});
  }
  return out;
}

}  // namespace

bool writeEvaluationJson(const std::string& path, const RunEvaluation& e, std::string* error) {
  using nlohmann::json;
  json j;
  j["format"] = "geofusion_evaluation_v1";
  j["scene"] = e.scene;
  j["method"] = e.method;
  j["config"] = e.config_yaml.empty() ? nlohmann::json(nullptr) : jsonOf(YAML::Load(e.config_yaml));
  j["image_size"] = {e.image_width, e.image_height};
  j["categories"] = json::array();
  for (const auto& c : e.categories) {
    const auto d = e.diameters_m.find(c.first);
    j["categories"].push_back(
        {{"id", c.first},
         {"name", c.second},
         {"diameter_m", d == e.diameters_m.end() ? json(nullptr) : json(d->second)}});
  }
  j["images"] = json::array();
  for (const auto& i : e.images) j["images"].push_back({{"id", i.first}, {"stamp", i.second}});
  j["unmatched_keyframes"] = e.unmatched_keyframes;
  j["annotations"] = annotationsJson(e);
  j["detections"] = detectionsJson(e);
  j["final_map"] = {{"objects", e.map_objects},
                    {"matched", e.map_matched},
                    {"true_objects", e.true_objects},
                    {"adds_m", e.map_adds_m},
                    {"alignment_rmse_m", e.alignment_rmse_m},
                    {"persistent_phantoms", e.persistent_phantoms},
                    {"surviving_phantoms", e.surviving_phantoms},
                    {"persistent_swaps", e.persistent_swaps},
                    {"surviving_swaps", e.surviving_swaps},
                    {"class_changes", e.class_changes},
                    {"classes_kept", e.classes_kept},
                    {"contacts", contactCountsJson(e)},
                    {"penetration_mm", scaled(e.penetration_m, 1000.0)},
                    {"gap_mm", scaled(e.gap_m, 1000.0)},
                    {"deepest_pair", e.deepest_pair},
                    {"widest_gap_pair", e.widest_gap_pair}};
  if (e.has_stability) j["stability"] = stabilityJson(e);
  if (e.has_scene_graph) j["scene_graph"] = sceneGraphJson(e);
  nlohmann::json clearance = nlohmann::json::array();
  for (const TableClearance& c : e.table_clearance)
    clearance.push_back({{"object", c.object},
                         {"truth_mm", 1000 * c.truth_m},
                         {"estimate_mm", 1000 * c.estimate_m}});
  j["table_clearance"] = clearance;
  j["lifecycle"] = lifecycleJson(e);
  j["trajectory"] = {{"ate_rmse_m", e.alignment_rmse_m},
                     {"odometry_ate_rmse_m", e.odometry_ate_rmse_m}};
  j["evaluation_config"] = evaluationConfigJson(e.evaluation_config);
  j["timings_ms"] = timingsJson(e.timings);
  j["final_solve_ms"] = e.final_solve.total_ms;
  j["warnings"] = e.warnings;
  j["recording_duration_s"] = e.recording_duration_s;
  j["wall_time_s"] = e.wall_time_s;
  j["realtime_factor"] = e.recording_duration_s > 0 ? e.wall_time_s / e.recording_duration_s : 0.0;
  j["peak_rss_mb"] = e.peak_rss_mb;
  j["contact_graph"] = {{"true_objects", graphObjectsJson(e.graph_true_objects, false)},
                        {"true_contacts", graphContactsJson(e.graph_true_contacts)},
                        {"estimated_objects", graphObjectsJson(e.graph_estimated_objects, true)},
                        {"estimated_contacts", graphContactsJson(e.graph_estimated_contacts)}};
  return writeTextAtomically(path, j.dump() + "\n", error);
}

std::string summarize(const RunEvaluation& e) {
  std::vector<double> totals;
  for (const StageTimings& t : e.timings) totals.push_back(t.total_ms);
  std::sort(totals.begin(), totals.end());
  auto quantile = [&](double q) {
    return totals.empty() ? 0.0
                          : totals[static_cast<std::size_t>(
                                std::lround(q * static_cast<double>(totals.size() - 1)))];
  };
  std::ostringstream s;
  char line[256];
  std::snprintf(line, sizeof(line), "%s on %s: %zu keyframes\n", e.method.c_str(), e.scene.c_str(),
                e.images.size());
  s << line;
  std::snprintf(line, sizeof(line),
                "  objects: %d in the map, %d of them true (of %d in the scene), %d false; "
                "ADD-S of the true ones %.1f mm mean\n",
                e.map_objects, e.map_matched, e.true_objects, e.map_objects - e.map_matched,
                1000 * mean(e.map_adds_m));
  s << line;
  std::snprintf(line, sizeof(line),
                "  camera trajectory (ATE RMSE): %.1f mm; the odometry it was given: %.1f mm\n",
                1000 * e.alignment_rmse_m, 1000 * e.odometry_ate_rmse_m);
  s << line;
  std::snprintf(line, sizeof(line),
                "  detector's persistent errors in the final map: %d of %d phantoms, %d of %d "
                "swapped classes\n",
                e.surviving_phantoms, e.persistent_phantoms, e.surviving_swaps, e.persistent_swaps);
  s << line;
  if (e.has_contacts) {
    std::snprintf(line, sizeof(line),
                  "  support contacts: %d found, %d of them true (%d of %d pairs true whatever "
                  "the type); %d true (%d between found objects and the table)\n",
                  e.estimated_contacts, e.correct_contacts, e.correct_contact_pairs,
                  e.estimated_contact_pairs, e.true_contacts, e.true_contacts_between_matched);
    s << line;
    s << "  every contact per kind, found / true of them / true:";
    for (ContactKind k : {ContactKind::kSupport, ContactKind::kLeaning, ContactKind::kSide}) {
      const ContactCounts& n = e.contacts_by_kind[static_cast<int>(k)];
      s << (k == ContactKind::kSupport ? " " : ", ") << toString(k) << " " << n.estimated << " / "
        << n.correct << " / " << n.truth;
    }
    s << "\n";
  }
  std::snprintf(line, sizeof(line),
                "  interpenetration %.1f mm mean, %.1f mm max (%zu touching pairs); gap under "
                "supported objects %.1f mm mean, %.1f mm max\n",
                1000 * mean(e.penetration_m), 1000 * maxOf(e.penetration_m), e.penetration_m.size(),
                1000 * mean(e.gap_m), 1000 * maxOf(e.gap_m));
  s << line;
  if (!e.deepest_pair.empty() && maxOf(e.penetration_m) > 0.0)
    s << "    deepest: " << e.deepest_pair << "\n";
  if (!e.widest_gap_pair.empty() && maxOf(e.gap_m) > 0.0)
    s << "    widest gap: " << e.widest_gap_pair << "\n";
  if (e.has_stability) {
    const physics::StabilityResult& m = e.stability;
    std::snprintf(line, sizeof(line),
                  "  stability (%.1f s of gravity): %d of %d true objects stable (%d start "
                  "interpenetrating); checked objects move %.1f mm mean, %.1f mm / %.1f deg max; "
                  "ground truth %d of %zu stable\n",
                  e.stability_config.duration_s, e.stability_true_stable, e.stability_true_objects,
                  e.stability_true_interpenetrating, 1000 * m.mean_translation_m,
                  1000 * m.max_translation_m, m.max_rotation_deg, e.stability_truth.stable,
                  e.stability_truth.bodies.size());
    s << line;
    if (!e.least_stable_pair.empty())
      s << "    least stable pair: " << e.least_stable_pair << " ("
        << std::lround(10000 * m.least_stable_pair_m) / 10.0 << " mm apart after it)\n";
  }
  if (!e.table_clearance.empty()) {
    double truth = 0.0, estimate = 0.0;
    for (const TableClearance& c : e.table_clearance) {
      truth += c.truth_m / e.table_clearance.size();
      estimate += c.estimate_m / e.table_clearance.size();
    }
    std::snprintf(line, sizeof(line),
                  "  on the table (%zu true objects): lowest point above the map's table %.1f mm "
                  "true, %.1f mm estimated (mean)\n",
                  e.table_clearance.size(), 1000 * truth, 1000 * estimate);
    s << line;
  }
  if (e.has_scene_graph) {
    std::snprintf(line, sizeof(line),
                  "  plan: %d of %d steps taking a true object unsafe, %d of them disturbing "
                  "another in physics (%d more under a missed object); free to pick: %d of %d "
                  "right (%d free in the truth)\n",
                  e.plan_unsafe_steps, e.plan_steps, e.plan_unsafe_steps_in_physics,
                  e.plan_steps_under_missed, e.free_correct, e.free_predicted, e.free_true);
    s << line;
    for (const std::string& step : e.unsafe_steps) s << "    unsafe step: " << step << "\n";
  }
  // The mean carries the solves made only every N-th keyframe (B-SLAM's stage I), which the
  // median does not see.
  std::snprintf(line, sizeof(line),
                "  time a keyframe: %.1f ms mean, %.1f ms median, %.1f ms p95; final solve %.1f "
                "ms; real-time factor %.2f\n",
                mean(totals), quantile(0.5), quantile(0.95), e.final_solve.total_ms,
                e.recording_duration_s > 0 ? e.wall_time_s / e.recording_duration_s : 0.0);
  s << line;
  for (const std::string& w : e.warnings) s << "  warning: " << w << "\n";
  return s.str();
}

}  // namespace geofusion
