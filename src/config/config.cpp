#include "geofusion/config/config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace geofusion {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
using Type = Setting::Type;

// The table: one row a setting. Rows are grouped by section in the template's order.
class Table {
 public:
  Table() {
    general();
    modelSet();
    input();
    keyframes();
    consistency();
    refinement();
    monitor();
    association();
    lifecycle();
    relocalisation();
    stageOne();
    relations();
    stageTwo();
    physics();
    sceneGraph();
    background();
    visualOdometry();
    node();
    visionMsgs();
  }
  std::vector<Setting> rows;

 private:
  template <typename F>
  void add(const std::string& key, Type type, double lo, double hi, const std::string& doc, F field,
           const std::string& reconfigure_name = "") {
    Setting s;
    s.key = key;
    s.type = type;
    s.min = lo;
    s.max = hi;
    s.doc = doc;
    s.reconfigure_name = reconfigure_name;
    s.field = [field](GeoFusionConfig& c) -> void* { return field(c); };
    rows.push_back(std::move(s));
  }
  template <typename F>
  void real(const std::string& key, double lo, double hi, const std::string& doc, F field,
            const std::string& reconfigure_name = "") {
    add(key, Type::kDouble, lo, hi, doc, field, reconfigure_name);
  }
  template <typename F>
  void integer(const std::string& key, double lo, double hi, const std::string& doc, F field,
               const std::string& reconfigure_name = "") {
    add(key, Type::kInt, lo, hi, doc, field, reconfigure_name);
  }
  template <typename F>
  void flag(const std::string& key, const std::string& doc, F field) {
    add(key, Type::kBool, 0, 1, doc, field);
  }
  template <typename F>
  void text(const std::string& key, const std::string& doc, F field,
            std::vector<std::string> choices = {}) {
    add(key, Type::kString, 0, 0, doc, field);
    rows.back().choices = std::move(choices);
  }
  template <typename F>
  void sigmoid(const std::string& key, const std::string& what, F field) {
    real(key + ".centre", 0.0, 1.0, what + ": centre of the modified sigmoid",
         [field](GeoFusionConfig& c) { return &field(c)->centre; });
    real(key + ".steepness", 0.1, 200.0, what + ": steepness of the modified sigmoid",
         [field](GeoFusionConfig& c) { return &field(c)->steepness; });
  }
  template <typename F>
  void loss(const std::string& key, const std::string& what, F field) {
    text(key + ".type", what + ": robust loss on whitened residuals",
         [field](GeoFusionConfig& c) { return &field(c)->type; }, {"none", "huber", "cauchy"});
    real(key + ".scale", 1e-3, 1e3, what + ": the loss's scale (whitened units)",
         [field](GeoFusionConfig& c) { return &field(c)->scale; });
  }

  void general() {
    text("method", "the method of the paper's comparison",
         [](GeoFusionConfig& c) { return &c.method; },
         {"geofusion", "rfront", "bslam", "fbf", "fbfr"});
  }
  void modelSet() {
    text("model_set.name",
         "object models: primitives (built in), ycb_video (config/models/ycb_video.yaml) or the "
         "path of a model-set YAML (docs/model_sets.md)",
         [](GeoFusionConfig& c) { return &c.model_set.name; });
    text("model_set.dir",
         "folder of the model set's meshes (\"\": beside the YAML; ycb_video: "
         "$GEOFUSION_YCB_DIR)",
         [](GeoFusionConfig& c) { return &c.model_set.dir; });
    auto f = [](GeoFusionConfig& c) { return &c.model_set.surface_features; };
    const std::string p = "model_set.surface_features.";
    real(p + "plane_angle_tolerance_deg", 0.1, 45,
         "hull facets within this angle join a plane, deg",
         [f](GeoFusionConfig& c) { return &f(c)->plane_angle_tolerance_deg; });
    real(p + "plane_distance_tolerance_m", 1e-4, 0.05, "... and within this distance, m",
         [f](GeoFusionConfig& c) { return &f(c)->plane_distance_tolerance_m; });
    real(p + "min_plane_area_fraction", 0, 1, "a plane covers at least this share of the hull",
         [f](GeoFusionConfig& c) { return &f(c)->min_plane_area_fraction; });
    real(p + "min_plane_width_m", 0, 0.5, "... and is at least this wide, m",
         [f](GeoFusionConfig& c) { return &f(c)->min_plane_width_m; });
    real(p + "min_edge_length_m", 0, 0.5, "shorter edges are dropped, m",
         [f](GeoFusionConfig& c) { return &f(c)->min_edge_length_m; });
    real(p + "edge_distance_tolerance_m", 1e-4, 0.05, "vertices this close to two planes: edge, m",
         [f](GeoFusionConfig& c) { return &f(c)->edge_distance_tolerance_m; });
    real(p + "min_edge_angle_deg", 0, 180, "planes closer in angle make no edge, deg",
         [f](GeoFusionConfig& c) { return &f(c)->min_edge_angle_deg; });
    real(p + "min_curved_area_fraction", 0, 1, "a cylinder side covers at least this share",
         [f](GeoFusionConfig& c) { return &f(c)->min_curved_area_fraction; });
    real(p + "min_side_share", 0, 1, "... with this share of normals perpendicular to the axis",
         [f](GeoFusionConfig& c) { return &f(c)->min_side_share; });
    real(p + "curved_normal_tolerance_deg", 0, 90, "... within this angle, deg",
         [f](GeoFusionConfig& c) { return &f(c)->curved_normal_tolerance_deg; });
    real(p + "max_radius_spread", 0, 1, "... and radius spread (std / mean) below this",
         [f](GeoFusionConfig& c) { return &f(c)->max_radius_spread; });
  }
  void input() {
    integer("input.queue_size", 1, 1000, "messages queued per synchronised input",
            [](GeoFusionConfig& c) { return &c.input.queue_size; });
    integer("input.frame_queue_size", 1, 1000,
            "synchronised frames waiting for the estimator's thread; a newer one pushes the "
            "oldest out (counted: queue overflow)",
            [](GeoFusionConfig& c) { return &c.input.frame_queue_size; });
    real("input.sync_max_interval_s", 0, 1, "largest stamp spread of a synchronised set, s",
         [](GeoFusionConfig& c) { return &c.input.sync_max_interval_s; });
    real("input.stale_after_s", 0.1, 600, "watchdog: an input silent this long is reported, s",
         [](GeoFusionConfig& c) { return &c.input.stale_after_s; });
    real("input.sync_timeout_s", 0.1, 600, "watchdog: inputs that never synchronise, s",
         [](GeoFusionConfig& c) { return &c.input.sync_timeout_s; });
    real("input.time_jump_tolerance_s", 0.01, 3600,
         "stamps going back more than this: time jumped (a looping bag), the input restarts, s",
         [](GeoFusionConfig& c) { return &c.input.time_jump_tolerance_s; });
    real(
        "input.tf_timeout_s", 0, 2, "wall-clock wait for the camera pose in TF, s",
        [](GeoFusionConfig& c) { return &c.input.tf_timeout_s; }, "tf_timeout_s");
    real("input.warn_period_s", 0.1, 3600, "throttle of repeated warnings, s",
         [](GeoFusionConfig& c) { return &c.input.warn_period_s; });
    real("input.min_score", 0, 1, "detections scoring below this are skipped before anything",
         [](GeoFusionConfig& c) { return &c.checks.min_score; });
    real("input.max_range_m", 0.1, 100, "detections farther from the camera are skipped, m",
         [](GeoFusionConfig& c) { return &c.checks.max_range_m; });
    real("input.unit_quaternion_tolerance", 1e-9, 0.5,
         "| |q| - 1 | above this: not a unit quaternion",
         [](GeoFusionConfig& c) { return &c.checks.unit_quaternion_tolerance; });
    integer("input.max_detections_per_frame", 1, 100000,
            "a frame's usable detections beyond this many are dropped, lowest scores first",
            [](GeoFusionConfig& c) { return &c.checks.max_detections; });
    real("input.max_odometry_gap_s", 0.01, 3600,
         "odometry samples around a frame further apart: the frame is dropped, not guessed, s",
         [](GeoFusionConfig& c) { return &c.ingestion.max_odometry_gap_s; });
    real("input.max_frame_age_s", 0.01, 3600,
         "a frame older than the newest input by more than this is dropped as stale, s",
         [](GeoFusionConfig& c) { return &c.ingestion.max_frame_age_s; });
    real("input.keyframe_budget_ms", 1, 1e6,
         "a keyframe taking longer is an overrun: counted, diagnostics WARN, ms",
         [](GeoFusionConfig& c) { return &c.ingestion.keyframe_budget_ms; });
  }
  void keyframes() {
    integer("keyframes.every_n_frames", 1, 1000, "a keyframe every N synchronised frames",
            [](GeoFusionConfig& c) { return &c.keyframes.every_n_frames; });
    real("keyframes.min_translation_m", 0, 10, "> 0: a keyframe once the camera moved this far, m",
         [](GeoFusionConfig& c) { return &c.keyframes.min_translation_m; });
    real("keyframes.min_rotation_rad", 0, 3.2, "> 0: ... or turned this much, rad",
         [](GeoFusionConfig& c) { return &c.keyframes.min_rotation_rad; });
  }
  void consistency() {
    auto f = [](GeoFusionConfig& c) { return &c.estimator.consistency; };
    real("consistency.eps_res", 1e-4, 0.2, "eps_res: observed this close on the ray: inlier, m",
         [f](GeoFusionConfig& c) { return &f(c)->eps_res; });
    real("consistency.eps_out", 1e-4, 0.5, "eps_out: observed this far behind: outlier, m",
         [f](GeoFusionConfig& c) { return &f(c)->eps_out; });
    sigmoid("consistency.inlier", "S_in, of the inlier ratio",
            [f](GeoFusionConfig& c) { return &f(c)->inlier; });
    sigmoid("consistency.outlier", "S_out, of 1 - the outlier ratio",
            [f](GeoFusionConfig& c) { return &f(c)->outlier; });
    sigmoid("consistency.occlusion", "S_occ, of 1 - the occlusion ratio",
            [f](GeoFusionConfig& c) { return &f(c)->occlusion; });
    integer("consistency.min_points", 1, 100000, "fewer rendered points with depth: undetermined",
            [f](GeoFusionConfig& c) { return &f(c)->min_points; });
    real("consistency.undetermined_score", 0, 1, "f_gc when undetermined",
         [f](GeoFusionConfig& c) { return &f(c)->undetermined_score; });
    integer("consistency.pixel_stride", 1, 16, "every n-th row and column of the rendered region",
            [f](GeoFusionConfig& c) { return &f(c)->pixel_stride; });
    integer("consistency.render_mesh_triangles", 12, 1000000,
            "triangles of the rendered mesh, at most",
            [f](GeoFusionConfig& c) { return &f(c)->render_mesh_triangles; });
    real("consistency.render_mesh_max_error_m", 0, 0.05, "... unless the surface moves more, m",
         [f](GeoFusionConfig& c) { return &f(c)->render_mesh_max_error_m; });
    integer("consistency.threads", 1, 16,
            "threads that score and refine a keyframe's detections (each its own renderer)",
            [f](GeoFusionConfig& c) { return &f(c)->threads; });
  }
  void refinement() {
    auto f = [](GeoFusionConfig& c) { return &c.estimator.refinement; };
    flag("refinement.enabled",
         "align each detection to the depth before it is judged (geofusion, fbfr; off: the "
         "paper's ablation)",
         [f](GeoFusionConfig& c) { return &f(c)->enabled; });
    integer("refinement.max_points", 10, 100000, "visible model surface points aligned, at most",
            [f](GeoFusionConfig& c) { return &f(c)->max_points; });
    integer("refinement.min_points", 3, 100000, "fewer with an observed depth: not refined",
            [f](GeoFusionConfig& c) { return &f(c)->min_points; });
    integer("refinement.iterations", 1, 100, "ICP rounds (projective association), at most",
            [f](GeoFusionConfig& c) { return &f(c)->iterations; });
    real("refinement.max_translation_m", 0, 1, "guard: a larger correction is refused, m",
         [f](GeoFusionConfig& c) { return &f(c)->max_translation_m; });
    real("refinement.max_rotation_rad", 0, 3.2, "guard: a larger rotation is refused, rad",
         [f](GeoFusionConfig& c) { return &f(c)->max_rotation_rad; });
    real("refinement.ray_window_m", 1e-4, 0.2,
         "first step along the ray: the densest window of this width of the distances, m",
         [f](GeoFusionConfig& c) { return &f(c)->ray_window_m; });
    real("refinement.gate_m", 1e-4, 0.5, "ICP pairs farther from the model surface are left out, m",
         [f](GeoFusionConfig& c) { return &f(c)->gate_m; });
    real("refinement.loss_scale_m", 1e-5, 0.1, "Cauchy loss scale of the ICP residuals, m",
         [f](GeoFusionConfig& c) { return &f(c)->loss_scale_m; });
    real("refinement.prior_sigma_rotation_rad", 1e-4, 3.2,
         "the detection as a prior: its rotation std, rad",
         [f](GeoFusionConfig& c) { return &f(c)->prior_sigma_rotation_rad; });
    real("refinement.prior_sigma_lateral_m", 1e-5, 1, "... and its std across the ray, m",
         [f](GeoFusionConfig& c) { return &f(c)->prior_sigma_lateral_m; });
    real("refinement.converged_translation_m", 0, 0.1, "converged when a round moves less, m",
         [f](GeoFusionConfig& c) { return &f(c)->converged_translation_m; });
    real("refinement.converged_rotation_rad", 0, 1, "... and turns less, rad",
         [f](GeoFusionConfig& c) { return &f(c)->converged_rotation_rad; });
    real("refinement.damping", 0, 100,
         "Levenberg-Marquardt damping of the steps (share of the diagonal)",
         [f](GeoFusionConfig& c) { return &f(c)->damping; });
    real("refinement.min_inlier_gain", -1, 1, "accepted when the inlier ratio gains more than this",
         [f](GeoFusionConfig& c) { return &f(c)->min_inlier_gain; });
    real("refinement.min_visible_share", 0, 1,
         "... judged when this share of the detection's surface is unhidden, else by f_gc",
         [f](GeoFusionConfig& c) { return &f(c)->min_visible_share; });
    real("refinement.ray_sigma_m", 1e-4, 0.5,
         "stage I: translation std of a refined measurement along the ray, m",
         [f](GeoFusionConfig& c) { return &f(c)->ray_sigma_m; });
  }
  void monitor() {
    auto f = [](GeoFusionConfig& c) { return &c.estimator.monitor; };
    integer("monitor.window_keyframes", 1, 10000,
            "rejected detections are counted over the last N keyframes",
            [f](GeoFusionConfig& c) { return &f(c)->window_keyframes; });
    integer("monitor.min_detections", 1, 100000, "fewer scored detections in them: no verdict",
            [f](GeoFusionConfig& c) { return &f(c)->min_detections; });
    real("monitor.inconsistent_below", 0, 1, "a detection whose f_gc is below this is rejected",
         [f](GeoFusionConfig& c) { return &f(c)->inconsistent_below; });
    real("monitor.warn_share", 0, 1, "warn when at least this share of them is rejected",
         [f](GeoFusionConfig& c) { return &f(c)->warn_share; });
  }
  void lifecycle() {
    auto f = [](GeoFusionConfig& c) { return &c.estimator.lifecycle; };
    real("lifecycle.free_space_outlier_ratio", 0, 1,
         "a mapped object not detected is gone where this share of its surface shows free space",
         [f](GeoFusionConfig& c) { return &f(c)->free_space_outlier_ratio; });
    real("lifecycle.max_occlusion_ratio", 0, 1, "... with at most this share of it hidden",
         [f](GeoFusionConfig& c) { return &f(c)->max_occlusion_ratio; });
    real("lifecycle.seen_inlier_ratio", 0, 1, "this share of its surface seen: the count restarts",
         [f](GeoFusionConfig& c) { return &f(c)->seen_inlier_ratio; });
    integer("lifecycle.free_space_keyframes", 1, 10000,
            "... removed after this many keyframes in a row showing free space",
            [f](GeoFusionConfig& c) { return &f(c)->free_space_keyframes; });
    integer("lifecycle.max_checks_per_keyframe", 0, 10000,
            "at most this many free-space checks (renders) a keyframe, least recently checked "
            "first (0: all)",
            [f](GeoFusionConfig& c) { return &f(c)->max_checks_per_keyframe; });
    real("lifecycle.detected_nearby_m", 0, 1,
         "a detection of its class this near counts as a sighting (free space cannot remove it "
         "that keyframe), m (0: off)",
         [f](GeoFusionConfig& c) { return &f(c)->detected_nearby_m; });
  }
  void association() {
    auto f = [](GeoFusionConfig& c) { return &c.estimator.association; };
    real(
        "association.min_detection_score", 0, 1, "detections below are ignored by the estimator",
        [](GeoFusionConfig& c) { return &c.estimator.min_detection_score; }, "min_score");
    real(
        "association.sigma_position_m", 0.001, 0.5, "Q: pose factor translation std, m",
        [f](GeoFusionConfig& c) { return &f(c)->sigma_position_m; }, "sigma_position_m");
    real(
        "association.sigma_rotation_rad", 0.01, 3.0, "Q: pose factor rotation std, rad",
        [f](GeoFusionConfig& c) { return &f(c)->sigma_rotation_rad; }, "sigma_rotation_rad");
    real(
        "association.eps_new", 1e-4, 0.9, "eps_new: below this likelihood, a new object",
        [f](GeoFusionConfig& c) { return &f(c)->eps_new; }, "eps_new");
    real(
        "association.eps_fp", 0.001, 1.0, "eps_fp: false-positive score above this: not in the map",
        [f](GeoFusionConfig& c) { return &f(c)->eps_fp; }, "eps_fp");
    integer("association.candidate_timeout_keyframes", 1, 10000,
            "candidates unseen this many keyframes are deleted",
            [f](GeoFusionConfig& c) { return &f(c)->candidate_timeout_keyframes; });
    real(
        "association.merge_ratio", 0.05, 1.0, "box collision ratio above which objects may merge",
        [f](GeoFusionConfig& c) { return &f(c)->merge_ratio; }, "merge_ratio");
    real(
        "association.merge_min_penetration_m", 0, 0.1,
        "... when their hulls interpenetrate this much, m",
        [f](GeoFusionConfig& c) { return &f(c)->merge_min_penetration_m; },
        "merge_min_penetration_m");
    real("association.merge_thin_fraction", 0, 1,
         "... or this share of the thinner object's extent",
         [f](GeoFusionConfig& c) { return &f(c)->merge_thin_fraction; });
    real("association.merge_cross_class_fraction", 0, 1,
         "objects of two classes merge only past this share of the thinner one's extent",
         [f](GeoFusionConfig& c) { return &f(c)->merge_cross_class_fraction; });
    integer("association.merge_co_measured_keyframes", 0, 100000,
            "... and, once both were measured with depth support at this many keyframes, only "
            "past merge_min_penetration_m (0: off)",
            [f](GeoFusionConfig& c) { return &f(c)->merge_co_measured_keyframes; });
    flag("association.merge_on_convex_parts",
         "interpenetration for merging on each model's convex parts (false: one hull each)",
         [f](GeoFusionConfig& c) { return &f(c)->merge_on_convex_parts; });
    flag("association.joint_assignment",
         "one Hungarian assignment per keyframe (false: the paper's greedy order)",
         [f](GeoFusionConfig& c) { return &f(c)->joint_assignment; });
    flag("association.class_by_consistency",
         "GeoFusion: a look-alike reported in place of an object: the depth decides its class "
         "(false: a new object)",
         [f](GeoFusionConfig& c) { return &f(c)->class_by_consistency; });
    real("association.class_vote_weight", 0, 10,
         "... each detection of a class adds this to its support (the votes as a prior)",
         [f](GeoFusionConfig& c) { return &f(c)->class_vote_weight; });
  }
  void stageOne() {
    auto f = [](GeoFusionConfig& c) { return &c.estimator.stage_one; };
    real(
        "stage_one.measurement_sigma_position_m", 0.001, 0.2, "object factor translation std, m",
        [f](GeoFusionConfig& c) { return &f(c)->measurement_sigma_position_m; },
        "measurement_sigma_position_m");
    real(
        "stage_one.measurement_sigma_rotation_rad", 0.005, 1.0, "object factor rotation std, rad",
        [f](GeoFusionConfig& c) { return &f(c)->measurement_sigma_rotation_rad; },
        "measurement_sigma_rotation_rad");
    real("stage_one.odometry_sigma_position_m", 1e-5, 1.0, "odometry factor translation std, m",
         [f](GeoFusionConfig& c) { return &f(c)->odometry_sigma_position_m; });
    real("stage_one.odometry_sigma_rotation_rad", 1e-5, 1.0, "odometry factor rotation std, rad",
         [f](GeoFusionConfig& c) { return &f(c)->odometry_sigma_rotation_rad; });
    loss("stage_one.measurement_loss", "object factors",
         [f](GeoFusionConfig& c) { return &f(c)->measurement_loss; });
    loss("stage_one.odometry_loss", "odometry factors",
         [f](GeoFusionConfig& c) { return &f(c)->odometry_loss; });
    integer("stage_one.max_iterations", 1, 1000, "Ceres iterations (warm-started)",
            [f](GeoFusionConfig& c) { return &f(c)->max_iterations; });
    integer(
        "stage_one.every_n_keyframes", 1, 100, "stage I every N keyframes (the paper: 10)",
        [f](GeoFusionConfig& c) { return &f(c)->every_n_keyframes; },
        "stage_one_every_n_keyframes");
    integer("stage_one.window_keyframes", 0, 100000, "latest N keyframe poses free (0: all)",
            [f](GeoFusionConfig& c) { return &f(c)->window_keyframes; });
    flag("stage_one.marginalise_outside_window",
         "older keyframes leave the problem, their measurements kept as object priors (cost "
         "bounded by the window)",
         [f](GeoFusionConfig& c) { return &f(c)->marginalise_outside_window; });
    flag("stage_one.adapt_noise",
         "GeoFusion: odometry and per-object measurement noise from the residuals of each solve",
         [f](GeoFusionConfig& c) { return &f(c)->adapt_noise; });
    real("stage_one.min_odometry_variance_factor", 1e-6, 1,
         "... the odometry's variance scaled down to at most this factor",
         [f](GeoFusionConfig& c) { return &f(c)->min_odometry_variance_factor; });
    real("stage_one.max_object_variance_factor", 1, 1e6,
         "... an object's measurement variance scaled up to at most this factor",
         [f](GeoFusionConfig& c) { return &f(c)->max_object_variance_factor; });
    real("stage_one.gate_chi2", 1, 1e6,
         "... a measurement's squared whitened residual beyond this: left out of the next solve",
         [f](GeoFusionConfig& c) { return &f(c)->gate_chi2; });
    flag("stage_one.axis_from_detections",
         "the angle about a can's axis (shape symmetric, label not) follows its detections where "
         "they agree; off: free",
         [f](GeoFusionConfig& c) { return &f(c)->axis_from_detections; });
    real("stage_one.axis_agreement_min", 0, 1,
         "... the detections agree when the resultant of their angles about the axis is at least "
         "this",
         [f](GeoFusionConfig& c) { return &f(c)->axis_agreement_min; });
  }
  void relations() {
    auto f = [](GeoFusionConfig& c) { return &c.estimator.contacts; };
    const std::string p = "relations.contacts.";
    real(p + "eps_n_pp", 0, 2, "P2P: |N_u . N_v + 1| below this",
         [f](GeoFusionConfig& c) { return &f(c)->eps_n_pp; });
    real(p + "eps_c_pp", 0, 0.1, "P2P: |N_u . (C_v - C_u)| below this, m",
         [f](GeoFusionConfig& c) { return &f(c)->eps_c_pp; });
    real(p + "eps_n_pc", 0, 1, "P2C: |N_p . N_c| below this",
         [f](GeoFusionConfig& c) { return &f(c)->eps_n_pc; });
    real(p + "eps_c_pc", 0, 0.1, "P2C: |N_p . (C_c - C_p) - r| below this, m",
         [f](GeoFusionConfig& c) { return &f(c)->eps_c_pc; });
    real(p + "eps_c_cc", 0, 0.1, "C2C: axis distance minus the radii below this, m",
         [f](GeoFusionConfig& c) { return &f(c)->eps_c_cc; });
    real(p + "eps_c_pe", 0, 0.1, "P2E: the other hull's nearest point within this of the plane, m",
         [f](GeoFusionConfig& c) { return &f(c)->eps_c_pe; });
    real(p + "edge_tolerance_m", 0, 0.05, "P2E: hull points this near the nearest make the edge, m",
         [f](GeoFusionConfig& c) { return &f(c)->edge_tolerance_m; });
    real(p + "max_penetration_m", 0, 0.1,
         "distance terms down to minus this (interpenetrating estimates) still make a contact, m",
         [f](GeoFusionConfig& c) { return &f(c)->max_penetration_m; });
    real(p + "eps_g", -1, 1, "support check: N . (-gravity) above this",
         [f](GeoFusionConfig& c) { return &f(c)->eps_g; });
    real(p + "side_max_tilt_deg", 0, 90,
         "a contact that is no support is side by side with its normal this near horizontal, "
         "leaning otherwise, deg",
         [f](GeoFusionConfig& c) { return &f(c)->side_max_tilt_deg; });
    real(p + "hysteresis", 1, 10,
         "a pair in contact at the last keyframe keeps it with the thresholds times this",
         [f](GeoFusionConfig& c) { return &f(c)->hysteresis; });
    real(p + "min_overlap_m", -0.1, 0.1, "projection overlap of the outlines, at least, m",
         [f](GeoFusionConfig& c) { return &f(c)->min_overlap_m; });
    real(p + "line_tolerance_m", 0, 0.1, "parallel line outlines meet within this, m",
         [f](GeoFusionConfig& c) { return &f(c)->line_tolerance_m; });
    flag(p + "support_only", "only support contacts, as the paper (false: leaning and side too)",
         [f](GeoFusionConfig& c) { return &f(c)->support_only; });
    auto g = [](GeoFusionConfig& c) { return &c.estimator.support_plane; };
    const std::string q = "relations.support_plane.";
    integer(q + "pixel_stride", 1, 64, "every n-th row and column of the depth image",
            [g](GeoFusionConfig& c) { return &g(c)->pixel_stride; });
    real(q + "max_range_m", 0.1, 20, "farther points are ignored, m",
         [g](GeoFusionConfig& c) { return &g(c)->max_range_m; });
    real(q + "distance_threshold_m", 1e-4, 0.2, "RANSAC inlier distance, m",
         [g](GeoFusionConfig& c) { return &g(c)->distance_threshold_m; });
    integer(q + "max_iterations", 1, 100000, "RANSAC iterations",
            [g](GeoFusionConfig& c) { return &g(c)->max_iterations; });
    real(q + "max_tilt_deg", 0, 90, "the plane normal within this angle of -gravity, deg",
         [g](GeoFusionConfig& c) { return &g(c)->max_tilt_deg; });
    integer(q + "min_inliers", 3, 1000000, "fewer: no plane at this keyframe",
            [g](GeoFusionConfig& c) { return &g(c)->min_inliers; });
    integer(q + "search_every_n_keyframes", 1, 100000,
            "a known plane is followed; RANSAC for the dominant one every n-th keyframe",
            [g](GeoFusionConfig& c) { return &g(c)->search_every_n_keyframes; });
    real(q + "thickness_m", 0.001, 1, "the grounded object: a slab this thick, m",
         [g](GeoFusionConfig& c) { return &g(c)->thickness_m; });
    add("relations.gravity", Type::kVector3, -kInf, kInf,
        "gravity direction in the map (= odom) frame, [x, y, z] (normalised)",
        [](GeoFusionConfig& c) { return &c.estimator.gravity; });
  }
  void relocalisation() {
    auto f = [](GeoFusionConfig& c) { return &c.estimator.relocalisation; };
    flag("relocalisation.enabled",
         "GeoFusion: on a revisit, the camera corrected against the map before association",
         [f](GeoFusionConfig& c) { return &f(c)->enabled; });
    real("relocalisation.inlier_m", 0.001, 1,
         "a detection is on a mapped object of its class within this, m",
         [f](GeoFusionConfig& c) { return &f(c)->inlier_m; });
    integer("relocalisation.min_inliers", 2, 1000,
            "a correction needs this many detections on objects",
            [f](GeoFusionConfig& c) { return &f(c)->min_inliers; });
    real("relocalisation.max_share_on_map", 0, 1,
         "searched only when fewer than this share of the detections are on objects uncorrected",
         [f](GeoFusionConfig& c) { return &f(c)->max_share_on_map; });
    real("relocalisation.min_gain", 1, 100,
         "applied when it brings this many times the detections onto objects (plus one)",
         [f](GeoFusionConfig& c) { return &f(c)->min_gain; });
    real("relocalisation.max_translation_m", 0, 100, "larger corrections refused, m",
         [f](GeoFusionConfig& c) { return &f(c)->max_translation_m; });
    real("relocalisation.max_rotation_deg", 0, 180, "larger corrections refused, deg",
         [f](GeoFusionConfig& c) { return &f(c)->max_rotation_deg; });
    real("relocalisation.drift_fraction", 0, 10,
         "odometry drift: translation error per metre travelled since the map last agreed",
         [f](GeoFusionConfig& c) { return &f(c)->drift_fraction; });
    real("relocalisation.drift_rad_per_m", 0, 10, "... heading error per metre travelled, rad",
         [f](GeoFusionConfig& c) { return &f(c)->drift_rad_per_m; });
    real("relocalisation.drift_rad_per_rad", 0, 10, "... heading error per radian turned",
         [f](GeoFusionConfig& c) { return &f(c)->drift_rad_per_rad; });
    real("relocalisation.gate_chi2", 0, 1e6,
         "corrections beyond this squared Mahalanobis distance against the drift refused",
         [f](GeoFusionConfig& c) { return &f(c)->gate_chi2; });
    integer("relocalisation.min_margin", 0, 1000,
            "applied with this many more detections on objects than the runner-up hypothesis",
            [f](GeoFusionConfig& c) { return &f(c)->min_margin; });
  }
  void stageTwo() {
    auto f = [](GeoFusionConfig& c) { return &c.estimator.stage_two; };
    real(
        "stage_two.prior_sigma_position_m", 0.001, 0.2, "object prior translation std, m",
        [f](GeoFusionConfig& c) { return &f(c)->prior_sigma_position_m; },
        "prior_sigma_position_m");
    real("stage_two.prior_sigma_rotation_rad", 0.001, 2, "object prior rotation std, rad",
         [f](GeoFusionConfig& c) { return &f(c)->prior_sigma_rotation_rad; });
    integer("stage_two.prior_full_weight_measurements", 0, 100000,
            "an object measured n times holds to its prior with weight sqrt(n / this), in "
            "[prior_min_weight, 1] (0: every object weight 1)",
            [f](GeoFusionConfig& c) { return &f(c)->prior_full_weight_measurements; });
    real("stage_two.prior_min_weight", 0.01, 1, "... the least weight of an object's prior",
         [f](GeoFusionConfig& c) { return &f(c)->prior_min_weight; });
    real(
        "stage_two.contact_sigma_distance_m", 0.0001, 0.05, "contact distance std (omega_p), m",
        [f](GeoFusionConfig& c) { return &f(c)->contact_sigma_distance_m; },
        "contact_sigma_distance_m");
    real(
        "stage_two.contact_sigma_direction", 0.001, 0.5, "contact direction std (omega_q)",
        [f](GeoFusionConfig& c) { return &f(c)->contact_sigma_direction; },
        "contact_sigma_direction");
    loss("stage_two.contact_loss", "contact factors",
         [f](GeoFusionConfig& c) { return &f(c)->contact_loss; });
    integer("stage_two.max_iterations", 1, 1000, "Ceres iterations",
            [f](GeoFusionConfig& c) { return &f(c)->max_iterations; });
    integer("stage_two.local_map_keyframes", 0, 100000,
            "relations, stage II and merging over the objects seen in the latest N keyframes "
            "and their contact partners (0: all objects)",
            [f](GeoFusionConfig& c) { return &f(c)->local_map_keyframes; });
    flag("stage_two.leaning_contacts", "leaning contacts join stage II (beside the supports)",
         [f](GeoFusionConfig& c) { return &f(c)->leaning_contacts; });
    flag("stage_two.side_contacts", "side-by-side contacts join stage II (beside the supports)",
         [f](GeoFusionConfig& c) { return &f(c)->side_contacts; });
    flag("stage_two.lift_out_of_support",
         "an object deeper through the support plane than the contacts reach is lifted onto it",
         [f](GeoFusionConfig& c) { return &f(c)->lift_out_of_support; });
    integer("stage_two.separation_rounds", 0, 10,
            "stage II solved again with separation factors while estimates interpenetrate, at "
            "most this often (0: off)",
            [f](GeoFusionConfig& c) { return &f(c)->separation_rounds; });
    real("stage_two.separation_min_depth_m", 0, 0.05,
         "shapes (convex parts) interpenetrating deeper than this get a separation factor, m",
         [f](GeoFusionConfig& c) { return &f(c)->separation_min_depth_m; });
    real("stage_two.separation_margin_m", 0, 0.01,
         "a separation factor parts the pair by its depth plus this, m",
         [f](GeoFusionConfig& c) { return &f(c)->separation_margin_m; });
    real("stage_two.separation_sigma_m", 1e-6, 0.1, "sigma of the separation factors, m",
         [f](GeoFusionConfig& c) { return &f(c)->separation_sigma_m; });
    flag("stage_two.separation_drop_stale",
         "a separation carried from an earlier keyframe is dropped once the pair's stage I poses "
         "no longer interpenetrate",
         [f](GeoFusionConfig& c) { return &f(c)->separation_drop_stale; });
    real("stage_two.separation_hull_max_depth_m", 0, 0.05,
         "the final solve parts pairs whose hulls (the physical check's bodies) interpenetrate "
         "at most this deep as hulls, deeper ones by their convex parts, m (0: parts only)",
         [f](GeoFusionConfig& c) { return &f(c)->separation_hull_max_depth_m; });
    integer("stage_two.seating_rounds", 0, 10,
            "the final solve checks the map in physics; objects it drops are seated by stage II "
            "on the contacts found where they came to rest, at most this often (0: off; "
            "docs/estimator.md, step 8)",
            [f](GeoFusionConfig& c) { return &f(c)->seating_rounds; });
    real("stage_two.seat_max_translation_m", 0, 1,
         "... an object is seated when it moved less than this in the check, m",
         [f](GeoFusionConfig& c) { return &f(c)->seat_max_translation_m; });
    real("stage_two.seat_max_rotation_deg", 0, 180, "... and turned less than this, deg",
         [f](GeoFusionConfig& c) { return &f(c)->seat_max_rotation_deg; });
    flag("stage_two.physics_contacts",
         "the final solve keeps a contact only where the stability check agrees (support, "
         "leaning: a normal force at rest; side: a contact point); needs a support plane",
         [f](GeoFusionConfig& c) { return &f(c)->physics_contacts; });
    real("stage_two.physics_min_force", 0, 100,
         "... a support or leaning contact bears at least this normal force at rest, N",
         [f](GeoFusionConfig& c) { return &f(c)->physics_min_force; });
    real("stage_two.physics_side_max_distance_m", 0, 0.02,
         "... a side contact's pair has a contact point at most this far apart at rest, m",
         [f](GeoFusionConfig& c) { return &f(c)->physics_side_max_distance_m; });
  }
  void background() {
    flag("background.enabled", "build the OctoMap of the static background",
         [](GeoFusionConfig& c) { return &c.background_enabled; });
    auto f = [](GeoFusionConfig& c) { return &c.background; };
    real("background.resolution_m", 0.002, 1, "voxel edge, m",
         [f](GeoFusionConfig& c) { return &f(c)->resolution_m; });
    real("background.max_range_m", 0.1, 20, "rays are cut here, m",
         [f](GeoFusionConfig& c) { return &f(c)->max_range_m; });
    integer("background.pixel_stride", 1, 64, "every n-th row and column",
            [f](GeoFusionConfig& c) { return &f(c)->pixel_stride; });
    integer("background.object_margin_px", 0, 100, "object masks grow by this many pixels",
            [f](GeoFusionConfig& c) { return &f(c)->object_margin_px; });
    real("background.object_margin_m", 0, 0.5, "points this close behind an object are left out, m",
         [f](GeoFusionConfig& c) { return &f(c)->object_margin_m; });
    real("background.region_half_extent_m", 0, 10000,
         "> 0: only the square of this half extent about the map origin (x, y; every height) is "
         "mapped (memory bounded by the region), m; 0: unbounded",
         [f](GeoFusionConfig& c) { return &f(c)->region_half_extent_m; });
    real("background.min_translation_m", 0, 100,
         "a keyframe is inserted when the camera moved this far since the last inserted one, m",
         [f](GeoFusionConfig& c) { return &f(c)->min_translation_m; });
    real("background.min_rotation_deg", 0, 360, "... or turned this far, degrees",
         [f](GeoFusionConfig& c) { return &f(c)->min_rotation_deg; });
    integer("background.max_interval_keyframes", 1, 100000,
            "... or this many keyframes passed (1: every keyframe)",
            [f](GeoFusionConfig& c) { return &f(c)->max_interval_keyframes; });
    integer("background.free_space_stride", 1, 64,
            "free space is cleared along the rays to every n-th sample in each direction (every "
            "sample still marks its voxel occupied)",
            [f](GeoFusionConfig& c) { return &f(c)->free_space_stride; });
    integer("background.mask_mesh_triangles", 4, 1000000,
            "object masks render each model simplified to about this many triangles",
            [f](GeoFusionConfig& c) { return &f(c)->mask_mesh_triangles; });
    flag("background.threaded",
         "the node inserts keyframes in a thread of its own (a keyframe arriving while one "
         "waits replaces it); the offline runner inserts every keyframe either way",
         [f](GeoFusionConfig& c) { return &f(c)->threaded; });
  }
  void visualOdometry() {
    auto f = [](GeoFusionConfig& c) { return &c.visual_odometry; };
    const std::string p = "visual_odometry.";
    integer(p + "features", 100, 20000, "ORB features a frame",
            [f](GeoFusionConfig& c) { return &f(c)->features; });
    integer(p + "pyramid_levels", 1, 16, "ORB scale levels",
            [f](GeoFusionConfig& c) { return &f(c)->pyramid_levels; });
    real(p + "scale_factor", 1.01, 4, "... and their ratio",
         [f](GeoFusionConfig& c) { return &f(c)->scale_factor; });
    integer(p + "fast_threshold", 1, 255, "FAST corner threshold, grey levels",
            [f](GeoFusionConfig& c) { return &f(c)->fast_threshold; });
    real(p + "min_depth_m", 0, 100, "features nearer get no 3D point, m",
         [f](GeoFusionConfig& c) { return &f(c)->min_depth_m; });
    real(p + "max_depth_m", 0.1, 100, "... or farther, m",
         [f](GeoFusionConfig& c) { return &f(c)->max_depth_m; });
    integer(p + "local_keyframes", 1, 100, "keyframes whose points make the local map",
            [f](GeoFusionConfig& c) { return &f(c)->local_keyframes; });
    real(p + "match_radius_px", 1, 500, "guided matching window, px",
         [f](GeoFusionConfig& c) { return &f(c)->match_radius_px; });
    integer(p + "max_descriptor_distance", 1, 256, "Hamming distance of a match, at most",
            [f](GeoFusionConfig& c) { return &f(c)->max_descriptor_distance; });
    real(p + "ratio", 0.1, 1, "best / second-best descriptor distance, at most",
         [f](GeoFusionConfig& c) { return &f(c)->ratio; });
    real(p + "ransac_reprojection_px", 0.1, 50, "PnP RANSAC inlier threshold, px",
         [f](GeoFusionConfig& c) { return &f(c)->ransac_reprojection_px; });
    integer(p + "ransac_iterations", 1, 100000, "PnP RANSAC iterations",
            [f](GeoFusionConfig& c) { return &f(c)->ransac_iterations; });
    integer(p + "min_inliers", 6, 10000, "fewer after the refinement: lost",
            [f](GeoFusionConfig& c) { return &f(c)->min_inliers; });
    real(p + "keyframe_tracked_fraction", 0, 1, "new keyframe below this share of inliers",
         [f](GeoFusionConfig& c) { return &f(c)->keyframe_tracked_fraction; });
    real(p + "keyframe_translation_m", 0, 100, "... or after this much motion, m",
         [f](GeoFusionConfig& c) { return &f(c)->keyframe_translation_m; });
    real(p + "keyframe_rotation_rad", 0, 3.2, "... or turn, rad",
         [f](GeoFusionConfig& c) { return &f(c)->keyframe_rotation_rad; });
    real(p + "max_speed_m_s", 0.01, 100, "faster apparent motion is a failure, m/s",
         [f](GeoFusionConfig& c) { return &f(c)->max_speed_m_s; });
    real(p + "max_turn_rad_s", 0.01, 100, "... or turn, rad/s",
         [f](GeoFusionConfig& c) { return &f(c)->max_turn_rad_s; });
    real(p + "pixel_sigma", 0.01, 100, "feature position noise for the covariance, px",
         [f](GeoFusionConfig& c) { return &f(c)->pixel_sigma; });
    integer(p + "relocalise_frames", 1, 100000, "lost this many frames: the map restarts",
            [f](GeoFusionConfig& c) { return &f(c)->relocalise_frames; });
    real(p + "restart_sigma_position_m", 0, 100, "covariance added at a restart, m",
         [f](GeoFusionConfig& c) { return &f(c)->restart_sigma_position_m; });
    real(p + "restart_sigma_rotation_rad", 0, 10, "... rad",
         [f](GeoFusionConfig& c) { return &f(c)->restart_sigma_rotation_rad; });
    flag(p + "local_bundle_adjustment",
         "at each keyframe, the window's poses and landmarks refined together (oldest fixed)",
         [f](GeoFusionConfig& c) { return &f(c)->local_bundle_adjustment; });
    integer(p + "ba_iterations", 1, 100, "solver iterations of each of its two passes",
            [f](GeoFusionConfig& c) { return &f(c)->ba_iterations; });
    real(p + "ba_depth_sigma_per_m2", 0, 1,
         "a feature's depth noise in it: this times depth^2, m (0: depth unused)",
         [f](GeoFusionConfig& c) { return &f(c)->ba_depth_sigma_per_m2; });
    flag(p + "depth_fallback",
         "a frame the features cannot place is aligned to the last placed frame's depth "
         "(point-to-plane ICP from the prediction) before it is given up",
         [f](GeoFusionConfig& c) { return &f(c)->depth_fallback; });
    real(p + "depth_fallback_max_rmse_m", 0.001, 0.1,
         "... kept when the point-to-plane RMS of the overlap (each term scaled to 1 m by "
         "1/depth^2) "
         "is at most this, m",
         [f](GeoFusionConfig& c) { return &f(c)->depth_fallback_max_rmse_m; });
    real(p + "depth_fallback_min_overlap", 0.05, 1,
         "... and at least this share of the frame's depth points has a partner",
         [f](GeoFusionConfig& c) { return &f(c)->depth_fallback_min_overlap; });
    real(p + "depth_fallback_min_constraint", 0, 1,
         "... and the geometry fixes every direction of motion: the smallest eigenvalue of the "
         "fit's information per point, about the points' centroid, rotation scaled by their spread "
         "(a "
         "bare plane gives 0)",
         [f](GeoFusionConfig& c) { return &f(c)->depth_fallback_min_constraint; });
  }
  void node() {
    flag("node.publish_map_to_odom", "broadcast map -> odom at every keyframe",
         [](GeoFusionConfig& c) { return &c.node.publish_map_to_odom; });
    text("node.save_on_shutdown", "save the map to this path prefix at shutdown (\"\": no)",
         [](GeoFusionConfig& c) { return &c.node.save_on_shutdown; });
    integer("node.autosave_every_keyframes", 0, 1000000,
            "save the map every N keyframes, as ~save_map does (0: not by count)",
            [](GeoFusionConfig& c) { return &c.node.autosave_every_keyframes; });
    real("node.autosave_every_s", 0, 1e6,
         "... or when this long passed since the last autosave and a keyframe came, s (0: not by "
         "time; both 0: no autosave)",
         [](GeoFusionConfig& c) { return &c.node.autosave_every_s; });
    text("node.autosave_prefix",
         "path prefix of the autosave (\"\": $ROS_HOME/geofusion/<node name>/autosave)",
         [](GeoFusionConfig& c) { return &c.node.autosave_prefix; });
    flag("node.resume_autosave",
         "at start, continue the autosave when this launch wrote it (a respawn), before "
         "~initial_map",
         [](GeoFusionConfig& c) { return &c.node.resume_autosave; });
    integer("node.background_publish_every", 1, 10000, "publish the background every N keyframes",
            [](GeoFusionConfig& c) { return &c.node.background_publish_every; });
    flag("node.publish_object_frames",
         "every object as TF frame <object_frame_prefix><id> under the map frame",
         [](GeoFusionConfig& c) { return &c.node.publish_object_frames; });
    text("node.object_frame_prefix", "TF frame name of an object: this prefix, then its id",
         [](GeoFusionConfig& c) { return &c.node.object_frame_prefix; });
    real("node.object_frames_rate_hz", 0, 1000,
         "the last keyframe's object frames are sent again at this rate, Hz (0: only at keyframes)",
         [](GeoFusionConfig& c) { return &c.node.object_frames_rate_hz; });
    real("node.object_frames_tolerance_s", 0, 10,
         "... stamped this far ahead of now, so a lookup at the current time succeeds, s",
         [](GeoFusionConfig& c) { return &c.node.object_frames_tolerance_s; });
    text("node.background_colour",
         "the background's colour in rviz: a bluish grey, lighter with height, or plain grey",
         [](GeoFusionConfig& c) { return &c.node.background_colour; }, {"height", "grey"});
  }
  void physics() {
    const std::string p = "physics.";
    auto f = [](GeoFusionConfig& c) { return &c.estimator.physics; };
    flag(p + "convex_parts",
         "stability check: bodies of the models' convex parts (true) or of their convex hulls, as "
         "the generator settles its scenes (false)",
         [f](GeoFusionConfig& c) { return &f(c)->convex_parts; });
    for (const physics::StabilitySetting& s : physics::stabilitySettings())
      real(p + s.key, s.min, s.max, s.doc,
           [field = s.field](GeoFusionConfig& c) { return &(c.estimator.physics.*field); });
  }
  void sceneGraph() {
    const std::string p = "scene_graph.";
    real(p + "over_share", 0, 1,
         "an object lies over another without a contact found when their footprints across "
         "gravity overlap by this share of the smaller one (docs/scene_graph.md)",
         [](GeoFusionConfig& c) { return &c.scene_graph.over_share; });
    real(p + "over_above_m", 0, 1, "... its centre and top higher by at least this, m",
         [](GeoFusionConfig& c) { return &c.scene_graph.over_above_m; });
    real(p + "over_gap_m", 0, 1, "... its bottom at most this far above the other's top, m",
         [](GeoFusionConfig& c) { return &c.scene_graph.over_gap_m; });
  }
  void visionMsgs() {
    text("vision_msgs.class_map",
         "vision_msgs/Detection3DArray class id -> model-set class: \"\" for the model set's own "
         "ids, else \"id: class_name, ...\" (only those ids are used)",
         [](GeoFusionConfig& c) { return &c.vision_msgs.class_map; });
  }
};

const Table& table() {
  static const Table t;
  return t;
}

// Shortest decimal text that reads back as the same double.
std::string numberText(double v) {
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  char buf[64];
  if (v == std::floor(v) && std::abs(v) < 1e15) {
    std::snprintf(buf, sizeof(buf), "%.0f", v);
    return buf;
  }
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof(buf), "%.*g", precision, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

std::string quoted(const std::string& s) {
  const bool plain = !s.empty() &&
                     s.find_first_of(":#{}[],&*?|<>=!%@`'\"\\ ") == std::string::npos &&
                     s != "true" && s != "false" && s != "null" && s != "~" &&
                     !std::isdigit(static_cast<unsigned char>(s[0])) && s[0] != '-' && s[0] != '.';
  if (plain) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

// Normalised choice text: lower case, without '-' and '_' ("R-Front" -> "rfront").
std::string normalised(const std::string& s) {
  std::string out;
  for (char c : s)
    if (c != '-' && c != '_') out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1] ? 1 : 0)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

std::string lastPart(const std::string& key) {
  const std::size_t dot = key.rfind('.');
  return dot == std::string::npos ? key : key.substr(dot + 1);
}

// The known key nearest to an unknown one: the same last part first (a flat "eps_fp" means
// association.eps_fp), else the smallest edit distance of the whole key or of its last part.
std::string nearestKey(const std::string& key) {
  const std::string last = lastPart(key);
  std::string best;
  std::size_t best_distance = std::numeric_limits<std::size_t>::max();
  for (const Setting& s : table().rows) {
    const std::size_t d =
        std::min(editDistance(key, s.key), 3 * editDistance(last, lastPart(s.key)));
    if (lastPart(s.key) == last) return s.key;
    if (d < best_distance) best_distance = d, best = s.key;
  }
  return best_distance <= std::max<std::size_t>(3, key.size() / 3) ? best : "";
}

template <typename T>
T& at(const Setting& s, GeoFusionConfig& c) {
  return *static_cast<T*>(s.field(c));
}

bool inRange(const Setting& s, double v) {
  return v >= s.min && v <= s.max;
}

// Sets `s` from a YAML scalar or sequence; the error names what is allowed.
bool setFromNode(const Setting& s, const YAML::Node& node, GeoFusionConfig* c, std::string* error) {
  auto bad = [&](const std::string& got) {
    *error = s.key + ": expected " + s.allowed() + ", got " + got;
    if (s.type == Type::kString && !node.IsScalar())
      *error += " (a text with ':' or '[' needs quotes: \"...\")";
    return false;
  };
  const std::string text =
      node.IsScalar() ? node.Scalar() : std::string("a ") + (node.IsMap() ? "map" : "list");
  try {
    switch (s.type) {
      case Type::kDouble: {
        if (!node.IsScalar()) return bad(text);
        double v;
        if (!YAML::convert<double>::decode(node, v) || !std::isfinite(v))
          return bad("'" + text + "'");
        if (!inRange(s, v)) return bad(text);
        at<double>(s, *c) = v;
        return true;
      }
      case Type::kInt: {
        double v;
        if (!node.IsScalar() || !YAML::convert<double>::decode(node, v) || v != std::floor(v))
          return bad("'" + text + "'");
        if (!inRange(s, v)) return bad(text);
        at<int>(s, *c) = static_cast<int>(v);
        return true;
      }
      case Type::kBool: {
        bool v;
        if (!node.IsScalar() || !YAML::convert<bool>::decode(node, v)) return bad("'" + text + "'");
        at<bool>(s, *c) = v;
        return true;
      }
      case Type::kString: {
        if (!node.IsScalar() && !node.IsNull()) return bad(text);
        const std::string v = node.IsNull() ? "" : node.Scalar();
        if (s.choices.empty()) {
          at<std::string>(s, *c) = v;
          return true;
        }
        for (const std::string& choice : s.choices) {
          if (normalised(choice) == normalised(v)) {
            at<std::string>(s, *c) = choice;
            return true;
          }
        }
        return bad("'" + v + "'");
      }
      case Type::kVector3: {
        if (!node.IsSequence() || node.size() != 3) return bad(text);
        Eigen::Vector3d v(node[0].as<double>(), node[1].as<double>(), node[2].as<double>());
        if (!v.allFinite() || v.norm() < 1e-9) return bad("a zero or non-finite vector");
        at<Eigen::Vector3d>(s, *c) = v.normalized();
        return true;
      }
    }
  } catch (const YAML::Exception&) {
    return bad("'" + text + "'");
  }
  return false;
}

// The method of `config.method` into the estimator (the loader's choices make it parse).
void resolveDerived(GeoFusionConfig* config) {
  parseMethod(config->method, &config->estimator.method);
}

// Walks a YAML map, setting every known key and reporting the rest.
void apply(const YAML::Node& node, const std::string& prefix, const std::string& source,
           GeoFusionConfig* config, ConfigReport* report) {
  for (const auto& kv : node) {
    const std::string key = prefix + kv.first.as<std::string>();
    const Setting* s = findSetting(key);
    if (s) {
      std::string error;
      if (!setFromNode(*s, kv.second, config, &error))
        report->errors.push_back(source + ": " + error);
      continue;
    }
    if (kv.second.IsMap()) {
      bool is_section = false;
      for (const Setting& row : table().rows) is_section |= row.key.rfind(key + ".", 0) == 0;
      if (is_section) {
        apply(kv.second, key + ".", source, config, report);
        continue;
      }
    }
    const std::string nearest = nearestKey(key);
    report->warnings.push_back(source + ": " + key + ": unknown" +
                               (nearest.empty() ? "" : ", did you mean " + nearest + "?"));
  }
}

}  // namespace

std::string Setting::valueText(const GeoFusionConfig& config) const {
  GeoFusionConfig& c = const_cast<GeoFusionConfig&>(config);
  switch (type) {
    case Type::kDouble: return numberText(at<double>(*this, c));
    case Type::kInt: return std::to_string(at<int>(*this, c));
    case Type::kBool: return at<bool>(*this, c) ? "true" : "false";
    case Type::kString: return quoted(at<std::string>(*this, c));
    case Type::kVector3: {
      const Eigen::Vector3d& v = at<Eigen::Vector3d>(*this, c);
      return "[" + numberText(v.x()) + ", " + numberText(v.y()) + ", " + numberText(v.z()) + "]";
    }
  }
  return "";
}

std::string Setting::allowed() const {
  switch (type) {
    case Type::kDouble: return "a number in [" + numberText(min) + ", " + numberText(max) + "]";
    case Type::kInt: return "an integer in [" + numberText(min) + ", " + numberText(max) + "]";
    case Type::kBool: return "true or false";
    case Type::kVector3: return "a non-zero vector [x, y, z]";
    case Type::kString: {
      if (choices.empty()) return "a string";
      std::string out = "one of ";
      for (std::size_t i = 0; i < choices.size(); ++i) out += (i ? ", " : "") + choices[i];
      return out;
    }
  }
  return "";
}

const std::vector<Setting>& settings() {
  return table().rows;
}

std::string nearestSettingKey(const std::string& key) {
  return nearestKey(key);
}

const Setting* findSetting(const std::string& key) {
  for (const Setting& s : table().rows)
    if (s.key == key) return &s;
  return nullptr;
}

const Setting* findReconfigurable(const std::string& name) {
  for (const Setting& s : table().rows)
    if (!s.reconfigure_name.empty() && s.reconfigure_name == name) return &s;
  return nullptr;
}

bool loadConfigText(const std::string& text, const std::string& source, GeoFusionConfig* config,
                    ConfigReport* report) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    report->errors.push_back(source + ": not YAML: " + e.what());
    return false;
  }
  if (root.IsNull()) return true;  // an empty file: the defaults
  if (!root.IsMap()) {
    report->errors.push_back(source + ": expected a map of settings at the top");
    return false;
  }
  const std::size_t errors_before = report->errors.size();
  GeoFusionConfig loaded = *config;
  apply(root, "", source, &loaded, report);
  if (report->errors.size() != errors_before) return false;
  resolveDerived(&loaded);
  *config = loaded;
  return true;
}

bool loadConfigFile(const std::string& path, GeoFusionConfig* config, ConfigReport* report) {
  std::ifstream file(path);
  if (!file) {
    report->errors.push_back(path + ": cannot read the file");
    return false;
  }
  std::stringstream text;
  text << file.rdbuf();
  return loadConfigText(text.str(), path, config, report);
}

bool setConfigValue(const std::string& key, const std::string& value, GeoFusionConfig* config,
                    std::string* error) {
  const Setting* s = findSetting(key);
  if (!s) {
    const std::string nearest = nearestKey(key);
    *error = key + ": unknown" + (nearest.empty() ? "" : ", did you mean " + nearest + "?");
    return false;
  }
  YAML::Node node;
  try {
    node = YAML::Load(value);
  } catch (const YAML::Exception&) {
    node = YAML::Node(value);
  }
  if (!setFromNode(*s, node, config, error)) return false;
  resolveDerived(config);
  return true;
}

bool setConfigNumber(const Setting& s, double value, GeoFusionConfig* config, std::string* error) {
  if (s.type != Type::kDouble && s.type != Type::kInt) {
    *error = s.key + ": not a number setting";
    return false;
  }
  return setFromNode(s, YAML::Node(numberText(value)), config, error);
}

double configNumber(const Setting& s, const GeoFusionConfig& config) {
  GeoFusionConfig& c = const_cast<GeoFusionConfig&>(config);
  if (s.type == Type::kDouble) return at<double>(s, c);
  if (s.type == Type::kInt) return at<int>(s, c);
  if (s.type == Type::kBool) return at<bool>(s, c) ? 1.0 : 0.0;
  return std::numeric_limits<double>::quiet_NaN();
}

std::string configYaml(const GeoFusionConfig& config, bool changed_only, bool comments,
                       const std::vector<std::string>& sections) {
  const GeoFusionConfig defaults;
  std::ostringstream out;
  std::vector<std::string> open;  // the sections written so far, outermost first
  for (const Setting& s : table().rows) {
    const std::string value = s.valueText(config);
    if (changed_only && value == s.valueText(defaults)) continue;
    const std::string section = s.key.substr(0, s.key.find('.'));
    if (!sections.empty() && std::find(sections.begin(), sections.end(), section) == sections.end())
      continue;
    std::vector<std::string> parts;
    std::stringstream path(s.key);
    for (std::string part; std::getline(path, part, '.');) parts.push_back(part);
    std::size_t common = 0;
    while (common < open.size() && common + 1 < parts.size() && open[common] == parts[common])
      ++common;
    open.resize(common);
    for (std::size_t i = common; i + 1 < parts.size(); ++i) {
      if (comments && i == 0) out << "\n";
      out << std::string(2 * i, ' ') << parts[i] << ":\n";
      open.push_back(parts[i]);
    }
    const std::string indent(2 * (parts.size() - 1), ' ');
    if (comments) {
      out << indent << "# " << s.doc << "; " << s.allowed()
          << (s.reconfigure_name.empty() ? "" : "; [dyn] " + s.reconfigure_name) << "\n";
    }
    out << indent << parts.back() << ": " << value << "\n";
  }
  return out.str();
}

std::string configDiff(const GeoFusionConfig& config) {
  const GeoFusionConfig defaults;
  std::string out;
  for (const Setting& s : table().rows) {
    const std::string value = s.valueText(config), base = s.valueText(defaults);
    if (value != base)
      out += (out.empty() ? "" : "\n") + s.key + ": " + value + " (default " + base + ")";
  }
  return out.empty() ? "defaults" : out;
}

}  // namespace geofusion
