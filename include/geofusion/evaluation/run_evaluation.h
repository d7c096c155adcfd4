// The benchmark's evaluator: one run of a method on one recording (run_offline results) against
// the recording's ground truth. It makes everything geometric - per-keyframe 2D boxes of true and
// estimated objects from projected model points, the ADD-S of every estimate against the true
// objects of its class, the final map matched to the true objects, its contact graph, its
// interpenetration and floating gaps - and writes it as an evaluation JSON file
// (docs/BENCHMARK.md). COCO mAP, precision and recall come from pycocotools on that file
// (src/tools/bench_report.py): the reference implementation, not re-implemented here.
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/common/image_box.h"
#include "geofusion/estimation/run_results.h"
#include "geofusion/estimation/scene_graph.h"
#include "geofusion/physics/stability.h"
#include "geofusion/simulation/dataset.h"

#include <Eigen/Geometry>

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace geofusion {

struct EvaluationConfig {
  /// Ground truth less visible than this is ignored (passed to pycocotools as a crowd).
  double min_visible_fraction = 0.1;
  /// Final map objects match true objects of their class one to one, ADD-S below this.
  double match_max_adds_m = 0.05;
  /// Object pairs (and objects and the table) closer than this count as touching.
  double touch_distance_m = 0.001;
  /// ADD-S of an estimate is computed against ground truth whose box overlaps its box at least
  /// this much: the report takes ADD-S of true positives at IoU 0.5 only (kept a little lower so
  /// that rounding never loses a pair).
  double adds_min_iou = 0.45;
  /// Results keyframes find their ground-truth frame by stamp within this.
  double stamp_tolerance_s = 0.005;
  /// Object lifecycle: a true object is in a keyframe's map when an estimate of its class lies
  /// within this distance of it (map frame aligned by the trajectories) ...
  double lifecycle_match_m = 0.05;
  /// ... it is well seen with at least this many keyframes at least this visible ...
  int well_seen_min_keyframes = 20;
  double well_seen_min_visible = 0.5;
  /// ... and lost when well seen yet not in the final map, or out of the map for more than this
  /// many keyframes after it was first mapped.
  int lost_absence_keyframes = 10;
  /// A phantom or a class swap of the detector is persistent when reported in at least this many
  /// keyframes; it survives when the final map has an object it explains: an unmatched estimate
  /// of the phantom's class within phantom_match_m of it, or an unmatched estimate of another
  /// class within lifecycle_match_m of the swapped object.
  int persistent_min_keyframes = 5;
  double phantom_match_m = 0.03;
  /// BOP's VSD of every estimate (vsd.h: two renders each, the test depth the true scene
  /// rendered once a keyframe); false: MSSD and MSPD only (evaluate_run --no-vsd).
  bool vsd = true;
};

/// A true object's life in the online map over a run.
struct ObjectLifecycle {
  int object = -1;              ///< ground-truth object index
  int well_seen_keyframes = 0;  ///< keyframes in which it is at least well_seen_min_visible
  int first_mapped = -1;        ///< first keyframe (results order) it is in the map; -1 never
  int departures = 0;           ///< times it left the map after being in it
  int returns = 0;              ///< departures followed by a return (flip-flops)
  int longest_absence = 0;      ///< longest stretch out of the map after first_mapped, keyframes
  bool in_final_map = false;    ///< matched in the final map
  bool lost = false;            ///< well seen, yet absent at the end or for too long
  /// A changed scene: the first keyframe without the object whose camera sees where it was (at
  /// least well_seen_min_visible of its old place unhidden; ground truth before issue 32: its
  /// centre in the image; results order), -1 while it stays or when it was never mapped.
  int removed_keyframe = -1;
  int last_mapped = -1;  ///< last keyframe it is in the map
  /// Keyframes from removed_keyframe until it left the map for good (0: gone at once); -1 when
  /// not removed, or when it is still in the map at the end (a ghost).
  int removal_latency = -1;
  bool ghost = false;  ///< taken away, yet in the map at the end
};

struct GroundTruthBox {
  int id = 0;     ///< unique within the evaluation, from 1
  int image = 0;  ///< keyframe index
  int class_id = 0;
  Box2d box;
  Box2d mask_box;      ///< box of its visible pixels (instance mask); empty when not recorded
  bool crowd = false;  ///< less than min_visible_fraction visible: ignored
  int object = -1;     ///< index of the scene object
  double visible_fraction = 0.0;
};

struct DetectionBox {
  int id = 0;
  int image = 0;
  int class_id = 0;
  Box2d box;
  double score = 0.0;
  int object_id = -1;  ///< the method's object id
  /// ADD-S (m) against each same-class, not ignored ground truth box of the image that its box
  /// overlaps at adds_min_iou or more: (ground truth id, value).
  std::vector<std::pair<int, double>> adds_m;
  /// ADD (m, no symmetry) against the same ground truth boxes as adds_m.
  std::vector<std::pair<int, double>> add_m;
  /// BOP's errors (bop_metrics.h; the appearance's symmetries) against every same-class ground
  /// truth of the image that is not ignored, whatever the boxes' overlap (BOP matches by error).
  struct BopError {
    int truth = 0;  ///< ground truth id
    double mssd_m = 0.0, mspd_px = 0.0;
    std::vector<double> vsd;  ///< one per tau of VsdConfig (empty: not computed)
  };
  std::vector<BopError> bop;
};

struct GraphObject {
  int id = -1;  ///< true objects: their index; estimated objects: their id
  std::string class_name;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< ground-truth map frame
  int match = -1;  ///< estimated objects: the true object matched, -1 none
};

struct GraphContact {
  int a = -1, b = -1;    ///< as GraphObject::id; a = -1 is the table / support plane
  std::string type;      ///< P2P, P2C, C2C, P2E
  std::string kind;      ///< support, leaning, side
  bool correct = false;  ///< estimated contacts: the true graph has it (pair and kind)
};

/// A true object on the table that the final map has: the lowest point of its model above the
/// table the map is judged on (the method's support plane, else the true table), at the true
/// pose and at the estimate (metres; negative: into the table). Where annotations sink objects
/// into the table (real frames), an estimate stood on the measured table is higher by as much.
struct TableClearance {
  std::string object;  ///< "class #id (true)"
  double truth_m = 0.0, estimate_m = 0.0;
};

/// Contacts of one kind in the final map against the truth, as (object pair, kind).
struct ContactCounts {
  int truth = 0, estimated = 0, correct = 0;
};

struct RunEvaluation {
  std::string scene, method;
  std::string config_yaml;  ///< the configuration the run was made with (from the results)
  EvaluationConfig evaluation_config;  ///< the protocol's own settings
  int image_width = 0, image_height = 0;
  std::vector<std::pair<int, std::string>> categories;  ///< (class id, name) of the model set
  /// BOP's object diameters (m, of the evaluation points) by class id: its MSSD thresholds.
  std::map<int, double> diameters_m;
  std::vector<std::pair<int, double>> images;  ///< (keyframe index, stamp)
  int unmatched_keyframes = 0;                 ///< results keyframes without a ground-truth frame
  std::vector<GroundTruthBox> ground_truth;
  std::vector<DetectionBox> detections;

  // The final map, aligned to the ground truth by the trajectories (Umeyama, no scale).
  Eigen::Isometry3d T_true_est = Eigen::Isometry3d::Identity();
  double alignment_rmse_m = 0.0;
  int map_objects = 0, map_matched = 0, true_objects = 0;
  std::vector<double> map_adds_m;  ///< of each matched object
  /// The camera trajectory against the truth after the alignment (ATE RMSE; alignment_rmse_m),
  /// and that of the odometry the method was given, aligned the same way at the same stamps.
  double odometry_ate_rmse_m = 0.0;
  /// The detector's persistent false objects and wrong classes, and how many are in the final
  /// map (EvaluationConfig::persistent_min_keyframes).
  int persistent_phantoms = 0, surviving_phantoms = 0;
  int persistent_swaps = 0, surviving_swaps = 0;
  /// Detections whose look-alike class the depth gave to an object (decision class_changed), and
  /// those it refused (class_kept), over the run (issue 51).
  int class_changes = 0, classes_kept = 0;
  /// Support contacts of the map against the true support contacts, as (object pair, type).
  bool has_contacts = false;  ///< false: the method infers none (FbF, B-SLAM, R-Front)
  int true_contacts = 0, estimated_contacts = 0, correct_contacts = 0;
  /// The same, per object pair whatever the contact type.
  int true_contact_pairs = 0, estimated_contact_pairs = 0, correct_contact_pairs = 0;
  int true_contacts_between_matched = 0;  ///< true contacts among matched objects and the table
  /// Every contact (support, leaning, side; indexed by ContactKind) as (object pair, kind).
  ContactCounts contacts_by_kind[3];
  std::vector<double> penetration_m;  ///< per touching or intersecting pair (object or table)
  std::vector<double> gap_m;          ///< per true support of a matched object
  /// Per matched object within 2 cm of the table (truth or estimate).
  std::vector<TableClearance> table_clearance;
  /// The pairs behind the maxima: "class #id (true|false) / class #id (...)" ("table" for the
  /// table), for finding what makes a map implausible; empty when there is none.
  std::string deepest_pair, widest_gap_pair;
  /// Physical stability (physics/stability.h): the final map on its support plane under gravity
  /// and, as the reference, the true scene on the true table, with the run's `physics` settings.
  bool has_stability = false;
  physics::StabilityConfig stability_config;
  physics::StabilityResult stability, stability_truth;
  /// Of the map's true (matched) objects: how many, how many stable, how many start
  /// interpenetrating (reported apart, not stable).
  int stability_true_objects = 0, stability_true_stable = 0, stability_true_interpenetrating = 0;
  std::map<int, int> stability_true_id;  ///< map object id -> the true object it matched
  std::string least_stable_pair;         ///< as deepest_pair, "table" for the plane
  /// The final map's support graph as a plan (estimation/scene_graph.h) against the truth's: the
  /// removal order's steps that take a true object; unsafe: a true object the map also has still
  /// rests or leans on it (the order's fault); under a missed object: only objects the map lacks
  /// do (the detection's fault). Free to pick: the map's true objects it calls free, of them
  /// free in the truth, and the true objects free in the truth the map has.
  bool has_scene_graph = false;
  SupportGraph scene_graph;
  int plan_steps = 0, plan_unsafe_steps = 0, plan_steps_under_missed = 0;
  std::string first_unsafe_step;  ///< "took class #id (true) before class #id resting on it"
  /// Each unsafe step checked in physics: the true objects left, with and without the one taken,
  /// under gravity; it disturbs the rest when another object then moves more by over the
  /// stability bounds. Unsafe steps that disturb nothing rest on a true contact labelled support
  /// or leaning where the objects do not bear on each other. One line per unsafe step.
  int plan_unsafe_steps_in_physics = 0;
  std::vector<std::string> unsafe_steps;
  int free_predicted = 0, free_correct = 0, free_true = 0;
  std::vector<GraphObject> graph_true_objects, graph_estimated_objects;
  std::vector<GraphContact> graph_true_contacts, graph_estimated_contacts;

  /// Per true object (empty for FbF, whose map is each keyframe's detections).
  bool has_lifecycle = false;
  std::vector<ObjectLifecycle> lifecycle;

  std::vector<StageTimings> timings;  ///< per keyframe
  StageTimings final_solve;           ///< the solve that made the final map (RunResults::finish)
  /// What makes a figure of this evaluation meaningless or suspect, one sentence each (no contacts
  /// in the ground truth, ...). evaluate_run prints them; the JSON has them as "warnings".
  std::vector<std::string> warnings;
  double recording_duration_s = 0.0, wall_time_s = 0.0, peak_rss_mb = 0.0;
};

/// Evaluates `results` against `gt`. False with `error` when nothing can be compared (no
/// keyframe of the results is in the ground truth).
bool evaluateRun(const GroundTruth& gt, const RunResults& results, const EvaluationConfig& config,
                 RunEvaluation* evaluation, std::string* error);

/// Writes the evaluation JSON (format geofusion_evaluation_v1, docs/BENCHMARK.md) atomically.
bool writeEvaluationJson(const std::string& path, const RunEvaluation& evaluation,
                         std::string* error);

/// A few lines for people: objects found and true, pose error, contacts, plausibility, time.
std::string summarize(const RunEvaluation& evaluation);

}  // namespace geofusion
