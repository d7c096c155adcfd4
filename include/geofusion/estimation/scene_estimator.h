// The scene estimator: keyframes (depth, intrinsics, odometry pose, checked detections) in;
// objects (class, 6D pose, scores), keyframe camera poses and contact relations out. Composes
// the modules of the paper's sections: geometric consistency (consistency.h), data association
// (association.h), stage I and stage II (optimization.h), geometric relations (relations.h).
// The four methods of the paper's comparison are compositions of the same stages (MethodStages),
// chosen by EstimatorConfig::method.
#pragma once

#include "geofusion/common/measurement.h"
#include "geofusion/estimation/association.h"
#include "geofusion/estimation/contacts.h"
#include "geofusion/estimation/depth_refinement.h"
#include "geofusion/estimation/detection_monitor.h"
#include "geofusion/estimation/object_lifecycle.h"
#include "geofusion/estimation/optimization.h"
#include "geofusion/estimation/relations.h"
#include "geofusion/estimation/relocalisation.h"
#include "geofusion/estimation/symmetry_axis.h"
#include "geofusion/model/object_model.h"
#include "geofusion/physics/stability.h"
#include "geofusion/render/consistency.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace geofusion {

class OffscreenRenderer;
class ConsistencyScorer;
class RefinementPool;
class HullCollider;

/// FbF: each keyframe's detections as they are. FbF-R: the same, depth-refined (what refinement
/// alone buys; not in the paper). B-SLAM: association by detector confidence, no false-positive
/// removal or merging, stage I only. R-Front: GeoFusion's association (geometric consistency,
/// false-positive removal, merging), no optimisation. GeoFusion: everything, with depth
/// refinement.
enum class Method {
  kFrameByFrame,
  kFrameByFrameRefined,
  kBaselineSlam,
  kRobustFrontEnd,
  kGeoFusion
};
const char* toString(Method method);  ///< "FbF", "FbF-R", "B-SLAM", "R-Front", "GeoFusion"
bool parseMethod(const std::string& name, Method* method);  ///< also accepts lower case

/// The stages a method composes, in the order a keyframe runs them: score the detections
/// (geometric consistency or the detector's score), then either report them as they are (FbF) or
/// associate them to the map's objects (Algorithm 1) with false-positive removal and merging,
/// stage I every few keyframes, geometric relations and stage II.
struct MethodStages {
  bool map_is_keyframe_detections = false;  ///< FbF: the keyframe's detections are the map
  bool depth_refinement = false;            ///< detections aligned to the depth first
  bool geometric_consistency = false;       ///< f_gc scores (else the detector's score)
  bool false_positive_removal = false;      ///< and merging of overlapping objects
  bool stage_one = false;                   ///< camera and object poses in the factor graph
  bool stage_one_noise_adaptation = false;  ///< noise scales from the residuals (not the paper)
  bool free_space_removal = false;          ///< objects the depth shows gone are removed
  bool relocalisation = false;              ///< the camera corrected against the map on revisits
  bool relations_and_stage_two = false;     ///< contacts and stage II (reported poses: stage II)
  bool class_by_consistency = false;        ///< a look-alike's class decided by the depth
};
MethodStages stagesOf(Method method);

struct EstimatorConfig {
  Method method = Method::kGeoFusion;
  ConsistencyConfig consistency;
  DepthRefinementConfig refinement;  ///< used by the methods whose stages include it
  DetectionMonitorConfig monitor;    ///< when most detections are rejected, say why
  LifecycleConfig lifecycle;         ///< removal of confirmed objects (GeoFusion)
  AssociationConfig association;
  StageOneConfig stage_one;
  ContactConfig contacts;
  SupportPlaneConfig support_plane;
  StageTwoConfig stage_two;
  RelocalisationConfig relocalisation;  ///< GeoFusion: the camera against the map on revisits
  /// The stability check (YAML section `physics`): the final solve's physical check
  /// (StageTwoConfig::seating_rounds), the evaluation and the results' summary.
  physics::StabilityConfig physics;
  Eigen::Vector3d gravity = -Eigen::Vector3d::UnitZ();  ///< in the map (= odom) frame
  double min_detection_score = 0.0;                     ///< detections below are ignored
};

struct Keyframe {
  double stamp_s = 0.0;
  Eigen::Isometry3d T_odom_cam = Eigen::Isometry3d::Identity();  ///< odometry camera pose
  PinholeIntrinsics K;
  DepthImageView depth;  ///< must stay valid during addKeyframe
  std::vector<ObjectMeasurement> detections;
};

/// An object of the map (or, for FbF, a detection of the keyframe).
struct ObjectEstimate {
  int id = -1;  ///< stable while the object exists; never reused
  std::shared_ptr<const ObjectModel> model;
  Eigen::Isometry3d T_map_obj = Eigen::Isometry3d::Identity();
  double existence = 0.0;  ///< ranking score in [0, 1]: 1 - false-positive score (FbF: detector)
  double false_positive = 1.0;    ///< f_j
  double best_consistency = 0.0;  ///< R_j
  int measurements = 0;           ///< n_j
  int first_keyframe = -1, last_keyframe = -1;
  /// Part of the map (false-positive score at most eps_fp); false for KeyframeResult::tentative.
  bool confirmed = true;
  /// How well the measurements pin the pose down: the covariance of their spread about the
  /// estimate (map frame; x, y, z in m², then the rotation vector in rad²) over their number.
  /// Rotation about a continuous symmetry axis is free and left at 0; zero below two
  /// measurements.
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  /// Stage I's measurements of it folded at their cameras' present poses (issue 52): what a
  /// saved map keeps of its history, the prior a resume continues from. Filled by snapshot()
  /// and finish() only (empty in the keyframes' results).
  FoldedMeasurements history;
};

struct StageTimings {
  double consistency_ms = 0.0;
  double association_ms = 0.0;
  /// Object lifecycle: false-positive removal, free-space checks (renders), merging.
  double lifecycle_ms = 0.0;
  double stage_one_ms = 0.0;
  double relations_ms = 0.0;
  double stage_two_ms = 0.0;
  double total_ms = 0.0;
};

/// How a keyframe's optimisation stage ended (not_run when it did not run at this keyframe).
struct StageReport {
  SolveStatus status = SolveStatus::kNotRun;
  int iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  bool ran() const { return status != SolveStatus::kNotRun; }
  bool failed() const { return ran() && !usable(status); }  ///< its result was not used
};

/// What became of one detection of a keyframe.
enum class DetectionDecision {
  kSkipped,       ///< unknown class, below the score threshold or a pose that is not finite
  kFrameObject,   ///< FbF: an object of this keyframe's map
  kNewObject,     ///< started an object that is in the map
  kNewCandidate,  ///< started a candidate (false-positive score too high for the map)
  kAssociated,    ///< measured an object of the map
  kCandidate,     ///< measured a candidate that is still not in the map
  kRemoved,       ///< its object was removed or merged away at this keyframe
  /// Issue 51: of another class than the object it would be mapped twice with; the depth kept
  /// the object's class (not a measurement of it) ...
  kClassKept,
  kClassChanged,  ///< ... or gave the object this detection's class (a measurement of it)
};
const char* toString(DetectionDecision decision);
bool parseDetectionDecision(const std::string& name, DetectionDecision* decision);

/// One detection of a keyframe: as it came, as it was used, its score and its fate.
struct DetectionReport {
  std::string class_name;
  double detector_score = 0.0;
  Eigen::Isometry3d T_cam_in = Eigen::Isometry3d::Identity();   ///< as detected
  Eigen::Isometry3d T_cam_out = Eigen::Isometry3d::Identity();  ///< as used (refined or not)
  RefinementOutcome refinement = RefinementOutcome::kNotAttempted;
  double ray_offset_m = 0.0;  ///< observed surface behind (+) the detected one, NaN: unknown
  double correction_translation_m = 0.0, correction_rotation_rad = 0.0;
  /// f_gc (or the detector's score for methods without it) at T_cam_out, -1 not scored; the
  /// ratios at T_cam_out (zero when not rendered).
  double consistency = -1.0;
  double r_in = 0.0, r_out = 0.0, r_occ = 0.0;
  DetectionDecision decision = DetectionDecision::kSkipped;
  int object = -1;  ///< the object (or candidate) id it went to
};

struct KeyframeResult {
  int keyframe = -1;
  double stamp_s = 0.0;
  Eigen::Isometry3d T_map_cam = Eigen::Isometry3d::Identity();
  std::vector<ObjectEstimate> objects;  ///< the estimate after this keyframe
  /// Objects seen but not (yet) confirmed: not part of the map, shown for inspection only.
  std::vector<ObjectEstimate> tentative;
  std::vector<int> removed_ids;   ///< objects removed or merged away at this keyframe
  std::vector<Removal> removals;  ///< ... each with its reason, in the same order
  /// Contacts among `objects` (indices into it; -1 = the support plane).
  std::vector<FeatureContact> contacts;
  std::vector<DetectionReport> detections;  ///< per input detection, in order
  /// Most detections of the last keyframes rejected as inconsistent with depth, and the likely
  /// cause (DetectionMonitor); empty when not.
  std::string detection_warning;
  int skipped_detections = 0;  ///< unknown class or below min score
  /// Whether the chained camera was corrected against the map before association, and by what.
  Relocalisation relocalisation;
  StageReport stage_one;  ///< a failed stage's result is not used
  StageReport stage_two;
  StageTimings timings;
};

class SceneEstimator {
 public:
  /// `renderer` may be shared with other users (calls are serialised); null makes one.
  SceneEstimator(const ModelSet& models, const EstimatorConfig& config,
                 std::shared_ptr<OffscreenRenderer> renderer = nullptr);
  ~SceneEstimator();

  /// Prepares every model now (the scoring meshes uploaded, the collision hulls built) rather
  /// than at its first detection: a live start without a first keyframe seconds over budget.
  void prepare();
  KeyframeResult addKeyframe(const Keyframe& keyframe);
  /// Continues a saved map (map_store.h) before the first keyframe: its objects become
  /// confirmed objects at their saved poses with their measurement counts and consistency (new
  /// detections associate with them; the free-space test removes those gone), their saved
  /// history (ObjectEstimate::history) stage I's prior on them as if the cameras that made it
  /// had left its window (without one only the new measurements place them), and the first
  /// keyframe's camera is placed through the saved map -> odom (the robot's odometry must
  /// continue in the same odom frame). False, changing nothing, once a keyframe was added.
  /// `next_object_id`: the saved map's next id (ids are never given out twice).
  /// `support`: the saved support plane; with its extent and inliers (saved since issue 52) the
  /// new keyframes' estimates are fused on from it, else it is found again from the first.
  bool resume(const std::vector<ObjectEstimate>& objects, const Eigen::Isometry3d& T_map_odom,
              int next_object_id = 0, const SupportPlane* support = nullptr);
  /// Final stage I and stage II over everything (the map a run ends with).
  KeyframeResult finish();
  /// The map as the last keyframe left it, without the final solve (what an autosave keeps),
  /// with each object's history.
  KeyframeResult snapshot() const;
  /// The id the next new object will get.
  int nextObjectId() const { return next_id_; }
  void reset();

  const EstimatorConfig& config() const { return config_; }
  void setConfig(const EstimatorConfig& config);  ///< thresholds and weights; method kept
  std::vector<ObjectEstimate> objects() const;
  const std::vector<FeatureContact>& contacts() const { return contacts_; }
  const std::vector<Eigen::Isometry3d>& trajectory() const { return T_map_cam_; }
  std::vector<double> keyframeStamps() const { return stamps_; }
  /// map -> odom correction at the latest keyframe (identity before the first).
  Eigen::Isometry3d T_map_odom() const;
  const SupportPlane& supportPlane() const { return support_; }
  int numKeyframes() const { return static_cast<int>(T_map_cam_.size()); }

 private:
  using Observation = TrackObservation;
  using Track = ObjectTrack;

  /// The keyframe's detections with the models of their classes and their scores.
  struct ScoredDetections {
    std::vector<int> usable;  ///< indices of the detections of known class and enough score
    std::vector<std::shared_ptr<const ObjectModel>> models;  ///< per detection (null: unusable)
    std::vector<double> score;                ///< f_gc, or the detector's score (-1: not scored)
    std::vector<DepthRefinement> refinement;  ///< per detection: the pose to use, its scores
    int skipped = 0;
    const Eigen::Isometry3d& pose(std::size_t k) const { return refinement[k].T_cam_obj; }
  };

  Eigen::Isometry3d appendCameraPose(const Keyframe& keyframe);
  Relocalisation relocaliseCamera(const ScoredDetections& detections);
  OdometryDrift driftSinceAnchor(const std::vector<LabelledPoint>& seen) const;
  ScoredDetections scoreDetections(const Keyframe& keyframe) const;
  std::vector<DetectionReport> reportDetections(const Keyframe& keyframe,
                                                const ScoredDetections& detections,
                                                const std::vector<int>& detection_object,
                                                const std::vector<int>& started,
                                                const std::vector<int>& removed,
                                                const std::vector<int>& contests) const;
  std::vector<int> mapKeyframeDetections(const Keyframe& keyframe,
                                         const ScoredDetections& detections, int t);
  std::vector<int> associateDetections(const Keyframe& keyframe, const ScoredDetections& detections,
                                       int t, std::vector<int>* started,
                                       std::vector<int>* contests);
  /// Issue 51: the usable detections left unassigned that another class's object would be
  /// mapped twice with are given to it (`assignment`), the depth deciding its class. Per usable
  /// detection: 0 not contested, 1 the object kept its class, 2 it took the detection's.
  std::vector<int> contestClasses(const Keyframe& keyframe, const ScoredDetections& detections,
                                  int t, std::vector<int>* assignment);
  Eigen::MatrixXd associationLikelihood(const Keyframe& keyframe,
                                        const ScoredDetections& detections) const;
  Track& startTrack(const std::shared_ptr<const ObjectModel>& model,
                    const Eigen::Isometry3d& T_map_obj, int t);
  ObjectEstimate estimateOf(const Track& track) const;
  Eigen::Matrix<double, 6, 6> poseSpread(const Track& track,
                                         const Eigen::Isometry3d& T_map_obj) const;
  const Eigen::Isometry3d& reportedPose(const Track& track) const;
  /// The ids of `measured` and of the confirmed tracks a detection of their class lies near
  /// (lifecycle.detected_nearby_m): the objects sighted at this keyframe.
  std::vector<int> sightedTracks(const ScoredDetections& detections,
                                 const std::vector<int>& measured) const;
  /// Tracks in the map: confirmed ones (all for methods without false-positive removal).
  std::vector<std::size_t> reportedTracks() const;
  bool stageOneDue(int t) const;
  /// Before stage I: the angle about a can's axis from its detections where they agree.
  void settleSymmetryAxis(Track* track);
  /// Stage I's measurement of `track` (object index `object`) made by its observation `o`.
  StageOneMeasurement stageOneMeasurement(const Track& track, const Observation& o,
                                          int object) const;
  StageReport runStageOne();
  /// The track's stage I measurements folded at the cameras' present poses (its history).
  FoldedMeasurements historyOf(const Track& track) const;
  /// `r` (the map after the last keyframe) with each object's history.
  KeyframeResult withHistory(KeyframeResult r) const;
  void adaptNoise(const std::vector<std::size_t>& reported,
                  const std::vector<Eigen::Isometry3d>& objects,
                  const std::vector<const ObjectModel*>& models,
                  const std::vector<StageOneMeasurement>& measurements,
                  const std::vector<std::pair<std::size_t, std::size_t>>& sources);
  /// Whether a track is in the local map (stage_two.local_map_keyframes) at the latest keyframe.
  bool recentlySeen(const Track& track) const;
  /// Positions in `reported` of the local map's objects: those recently seen and their contact
  /// partners (all with `everything`).
  std::vector<std::size_t> localMap(const std::vector<std::size_t>& reported,
                                    bool everything) const;
  void updateSupportPlane(const Keyframe& keyframe);
  /// Relations and stage II over the local map (`keyframe` null: the final solve, every object).
  StageReport runRelationsAndStageTwo(const Keyframe* keyframe, StageTimings* timings);
  /// Stage II over the `local` ones of the `reported` tracks (T_refined in/out), each estimate
  /// through the support plane lifted onto it, with the separations carried from earlier
  /// keyframes, then, while estimates interpenetrate (StageTwoConfig::separation_rounds), the
  /// interpenetrating objects and their contact neighbours solved again with new ones (the rest
  /// held). The summary is the first solve's with every solve's iterations; a failed re-solve
  /// gives its status and leaves the poses before it. The `final_solve` (after the last merge)
  /// parts two objects of one class as well.
  StageTwoSummary solveStageTwo(const std::vector<std::size_t>& local,
                                const std::vector<std::size_t>& reported,
                                const std::vector<FeatureContact>& contacts,
                                const PosedModel* ground, bool final_solve);
  /// The relations found over the `local` tracks (`local_contacts`, local indices) as the map's
  /// contacts, with those kept that the relations could not find again (an end outside the local
  /// map) between objects that still exist.
  void setContacts(const std::vector<FeatureContact>& local_contacts,
                   const std::vector<std::size_t>& local, const std::vector<std::size_t>& reported);
  /// The final solve's physical check (StageTwoConfig::seating_rounds): the `local` tracks in
  /// the stability check; those it drops within the bounds get, in the solve's `contacts` (local
  /// indices, in/out), the contacts found where they came to rest in place of theirs, and stage
  /// II is solved again (solveStageTwo) with them starting there. False without a support
  /// plane, when none was dropped (or none has a contact where it came to rest) or the solve
  /// failed (the poses and separations then as before).
  bool seatDropped(const std::vector<std::size_t>& local, const std::vector<std::size_t>& reported,
                   const PosedModel* ground, std::vector<FeatureContact>* contacts);
  /// The `local` tracks at their refined poses in the stability check on the support plane (the
  /// bodies in that order, by track id).
  physics::StabilityResult checkLocalStability(const std::vector<std::size_t>& local,
                                               const std::vector<std::size_t>& reported) const;
  /// The paper's physical relationship check on the relations (StageTwoConfig::
  /// physics_contacts): the `local` tracks at their refined poses in the stability check; of
  /// the `contacts` (local indices) between objects it can judge (simulated, not starting
  /// inside another, standing), a support or leaning contact is kept where the pair bears on
  /// each other at rest (a normal force of at least physics_min_force), a side contact where
  /// they touch (a contact point within physics_side_max_distance_m); the others are kept as
  /// they are.
  std::vector<FeatureContact> physicsAgreedContacts(
      const std::vector<std::size_t>& local, const std::vector<std::size_t>& reported,
      const std::vector<FeatureContact>& contacts) const;
  /// The contacts (local indices) of the `dropped` objects at their `rested` poses; a dropped
  /// object without one is taken back (not dropped, its rested pose its refined one) and the
  /// contacts found again.
  std::vector<FeatureContact> restingContacts(std::vector<PosedModel>* rested,
                                              std::vector<bool>* dropped,
                                              const std::vector<Track*>& solved,
                                              const PosedModel* ground) const;
  /// The carried separations between objects of `index_of_id` (track id -> local index into
  /// `solved`; -1 the ground), in local indices; with separation_drop_stale, only those whose
  /// pair still interpenetrates at its stage I poses.
  std::vector<Separation> localSeparations(const std::map<int, int>& index_of_id,
                                           const std::vector<Track*>& solved,
                                           bool has_ground) const;
  void liftOutOfSupport(Track* track) const;
  void keepSeparations(const std::vector<Separation>& separations,
                       const std::vector<Track*>& solved);
  KeyframeResult result(int keyframe, double stamp) const;

  EstimatorConfig config_;
  MethodStages stages_;
  std::map<std::string, std::shared_ptr<const ObjectModel>> models_;
  std::unique_ptr<ConsistencyScorer> scorer_;
  std::unique_ptr<DepthRefiner> refiner_;
  std::unique_ptr<RefinementPool> pool_;  ///< scoring methods: consistency.threads - 1 workers
  DetectionMonitor monitor_;
  std::unique_ptr<HullCollider> collider_;
  std::vector<Track> tracks_;
  AppearanceModels appearance_models_;  ///< the models with their appearance symmetry
  int next_id_ = 0;
  std::vector<Eigen::Isometry3d> T_map_cam_, T_odom_cam_;
  double odometry_variance_ = 1.0;  ///< stage I odometry variance factor (noise adaptation)
  std::vector<double> stamps_;
  Eigen::Isometry3d T_map_odom_start_ = Eigen::Isometry3d::Identity();  ///< resume()
  /// T_odom_cam_ = T_odom_fix_ x the robot's odometry: relocalisations replace the increments
  /// they correct.
  Eigen::Isometry3d T_odom_fix_ = Eigen::Isometry3d::Identity();
  /// The last keyframe whose detections agreed with the map (or that was relocalised): the
  /// odometry's drift is counted from it. -1: unknown (a resumed map not yet relocalised).
  int relocalisation_anchor_ = 0;
  SupportPlane support_;
  std::shared_ptr<ObjectModel> support_model_;
  Eigen::Isometry3d T_map_support_ = Eigen::Isometry3d::Identity();
  std::vector<FeatureContact> contacts_;        ///< reported-track indices; -1 = support
  std::vector<FeatureContact> contacts_by_id_;  ///< contacts_ with track ids (-1 = support)
  /// Pairs in contact at the last keyframe, as track ids (-1 = the support), for hysteresis.
  std::vector<std::pair<int, int>> held_contacts_;
  std::vector<ObjectEstimate> frame_objects_;  ///< FbF: this keyframe's detections
  /// Separations (stage II) as track ids (-1 = the support), carried to the next keyframes
  /// while the pair stays within a centimetre of parting, so that stage II is solved once a
  /// keyframe where nothing new interpenetrates.
  std::vector<Separation> separations_by_id_;
};

}  // namespace geofusion
