#pragma once
// The object lifecycle (the paper's false-positive removal and merging, and removal on evidence):
// the map's objects and candidates as tracks, started from detections, confirmed by their
// false-positive score, dropped as candidates unseen for too long, removed when the depth shows
// free space where they stood, merged when one object is mapped twice. The scene estimator calls
// these steps at every keyframe (docs/estimator.md); each is a function of the tracks and its
// configuration, tested on its own (test/estimation/test_object_lifecycle.cpp).

#include "geofusion/estimation/association.h"
#include "geofusion/estimation/optimization.h"
#include "geofusion/model/object_model.h"
#include "geofusion/render/consistency.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace geofusion {

class HullCollider;

/// When a mapped object is gone (picked up, moved): only on evidence. A confirmed object in view
/// that no detection measured is rendered at its pose against the depth image; when at least
/// free_space_outlier_ratio of its visible surface shows the observed surface behind it (free
/// space where it should be), while at most max_occlusion_ratio of it is hidden, for
/// free_space_keyframes keyframes in a row, it leaves the map. A keyframe that sees its surface
/// (inlier ratio at least seen_inlier_ratio) resets the count; not being detected never removes it.
struct LifecycleConfig {
  double free_space_outlier_ratio = 0.5;
  double max_occlusion_ratio = 0.5;
  double seen_inlier_ratio = 0.5;
  int free_space_keyframes = 2;  ///< 3 before issue 45 (see detected_nearby_m)
  /// At most this many of the checks (renders) a keyframe, the objects checked least recently
  /// first: the cost stays bounded when many mapped objects go undetected (biased or missing
  /// detections). 0: every undetected object in view, every keyframe.
  int max_checks_per_keyframe = 8;
  /// A detection of an object's class within this distance of it (centres, any f_gc) counts as
  /// a sighting, as a measurement does: the free-space count restarts. A detector still
  /// reporting the object a few centimetres off (a colour-only estimator's error, which the
  /// depth refutes at both poses) is not evidence of absence (issue 45). 0: off.
  double detected_nearby_m = 0.05;
};

/// Why an object (or candidate) left the map.
enum class RemovalReason {
  kCandidateTimeout,  ///< a candidate (false-positive score above eps_fp) unseen for too long
  kSeenAbsent,        ///< the depth showed free space where it stood (lifecycle.*)
  kMerged,            ///< merged into an overlapping object (`into`)
};
const char* toString(RemovalReason reason);
bool parseRemovalReason(const std::string& name, RemovalReason* reason);

struct Removal {
  int id = -1;
  RemovalReason reason = RemovalReason::kCandidateTimeout;
  int into = -1;  ///< kMerged: the object it went into
};

/// One measurement of a track: the detection (refined or not) that associated with it.
struct TrackObservation {
  int keyframe = 0;
  Eigen::Isometry3d T_cam_obj = Eigen::Isometry3d::Identity();
  double consistency = 0.0;  ///< f_gc (B-SLAM: the detector score)
  bool refined = false;      ///< depth-refined: tight along the ray in stage I
  bool gated = false;        ///< left out of stage I (residual beyond the gate)
  bool folded = false;       ///< its camera left stage I's window: in ObjectTrack::folded
};

/// An object of the map (confirmed) or a candidate.
struct ObjectTrack {
  int id = -1;
  std::shared_ptr<const ObjectModel> model;
  /// Set while its detections agree about the angle about the shape's axis (symmetry_axis.h):
  /// the model with its appearance symmetry, which stage I and II are given instead.
  std::shared_ptr<const ObjectModel> appearance_model;
  /// The model whose symmetry the optimisation uses: appearance_model when set, else model.
  const ObjectModel* symmetryModel() const {
    return appearance_model ? appearance_model.get() : model.get();
  }
  Eigen::Isometry3d T_stage_one = Eigen::Isometry3d::Identity();  ///< stage I / initial
  Eigen::Isometry3d T_refined = Eigen::Isometry3d::Identity();    ///< stage II
  std::vector<TrackObservation> observations;
  /// Marginalising outside stage I's window: the observations whose cameras left it (and the
  /// prior below).
  FoldedMeasurements folded;
  /// Stage I's measurements before a resume (saved with the map as they were folded at their
  /// cameras' poses): a resumed object's history, part of `folded` from the start.
  FoldedMeasurements prior;
  double best_consistency = 0.0;
  int first_keyframe = -1, last_keyframe = -1;
  bool confirmed = false;        ///< false-positive score at most eps_fp: part of the map
  double variance = 1.0;         ///< stage I measurement variance factor (noise adaptation)
  int free_space_keyframes = 0;  ///< keyframes in a row showing free space where it should be
  int last_checked = -1;         ///< keyframe of its last free-space check (rendered)
  int prior_measurements = 0;    ///< measurements made before a resume (saved with the map)
  /// The depth's support of those measurements: the map keeps their count and the best
  /// consistency only, so their product stands for it.
  double prior_evidence = 0.0;
  /// Issue 51, per class reported at this place: the depth's support where two classes competed
  /// (the sum of its model's f_gc) and the detections of it (the object's own class included).
  struct ClassEvidence {
    double consistency = 0.0;
    int votes = 0;
  };
  std::map<std::string, ClassEvidence> class_evidence;
  int class_changes = 0;  ///< times the depth changed its class
  /// n_j: its measurements, those before a resume included.
  int measurementCount() const {
    return static_cast<int>(observations.size()) + prior_measurements;
  }
  Eigen::Vector3d box_centre = Eigen::Vector3d::Zero();  ///< model-frame bounding box
  Eigen::Vector3d box_half = Eigen::Vector3d::Zero();
  /// How much the depth supported it over all its measurements: the sum of their f_gc (with
  /// prior_evidence for those before a resume).
  double depthEvidence() const;
};

/// A new track of `model` at `T_map_obj`, first seen at `keyframe` (-1: from a saved map).
ObjectTrack makeTrack(int id, const std::shared_ptr<const ObjectModel>& model,
                      const Eigen::Isometry3d& T_map_obj, int keyframe);

/// The track becomes an object of `model` (its box and appearance follow; counted in
/// class_changes).
void changeClass(ObjectTrack* track, const std::shared_ptr<const ObjectModel>& model);

/// Issue 51: a detection of another class (`other`, scoring `f_other` at its pose) competes for
/// the track's place, its own model scoring `f_held` there: both added to its class_evidence
/// (the challenger's vote too), and true when the challenger's support (consistency +
/// vote_weight x votes) now exceeds the held class's (the caller changes the class).
bool challengerWins(ObjectTrack* track, const std::string& other, double f_other, double f_held,
                    double vote_weight);

/// The pose a track is reported (and checked) at: stage II's or stage I's, by method.
using TrackPose = std::function<const Eigen::Isometry3d&(const ObjectTrack&)>;

/// The paper's false-positive removal: the tracks measured at this keyframe (`touched` ids) are
/// confirmed when their false-positive score is at most eps_fp; a candidate unseen for more than
/// candidate_timeout_keyframes is dropped (kCandidateTimeout).
void confirmOrTimeOut(std::vector<ObjectTrack>* tracks, const std::vector<int>& touched,
                      int keyframe, const AssociationConfig& config, std::vector<Removal>* removed);

/// What the depth shows at a track's reported pose (ConsistencyScorer::score at that pose).
using FreeSpaceLook = std::function<ConsistencyResult(const ObjectTrack&)>;

/// Removal on evidence (LifecycleConfig): confirmed tracks no detection measured (`measured`
/// ids) are looked at, least recently checked first, at most max_checks_per_keyframe of those in
/// view; free space for free_space_keyframes keyframes in a row removes one (kSeenAbsent).
void removeSeenAbsent(std::vector<ObjectTrack>* tracks, const std::vector<int>& measured,
                      int keyframe, const LifecycleConfig& config, const FreeSpaceLook& look,
                      std::vector<Removal>* removed);

/// Whether a and b (at T_a, T_b) are one object mapped twice: their boxes overlap by more than
/// merge_ratio and their hulls interpenetrate by more than neighbours in clutter can (scaled
/// down for thin objects; across classes, merge_cross_class_fraction of the thinner extent, and
/// merge_min_penetration_m once the depth supported both at merge_co_measured_keyframes).
bool mappedTwice(const ObjectTrack& a, const Eigen::Isometry3d& T_a, const ObjectTrack& b,
                 const Eigen::Isometry3d& T_b, const AssociationConfig& config,
                 HullCollider* collider);

/// Keyframes at which both a and b were measured with the depth supporting the measurement
/// (f_gc > 0).
int coMeasuredKeyframes(const ObjectTrack& a, const ObjectTrack& b);

/// The observations of `dropped` (same class) taken into `kept`, one per keyframe (kept's own
/// wins); best consistency, measurements before a resume and keyframe span combined. The merged
/// object keeps the older identity: when `dropped` was mapped first, the two swap ids.
void absorb(ObjectTrack* dropped, ObjectTrack* kept);

/// Merging of overlapping tracks until none is mapped twice; a pair neither of which was
/// `recently_seen` is not checked again. One class: the lower false-positive score stays and
/// absorbs the other under the older id; two classes: the one the depth supported more stays
/// (kMerged).
void mergeOverlapping(std::vector<ObjectTrack>* tracks, const AssociationConfig& config,
                      HullCollider* collider, const TrackPose& pose,
                      const std::function<bool(const ObjectTrack&)>& recently_seen,
                      std::vector<Removal>* removed);

}  // namespace geofusion
