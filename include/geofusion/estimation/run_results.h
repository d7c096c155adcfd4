// The results of running the estimator over a recording, and the YAML file they are written to
// (docs/results.md): every keyframe's online estimate, the final map with its contacts, the
// estimated trajectory and per-stage timings. Written by the offline runner; read by the
// benchmark's evaluator.
#pragma once

#include "geofusion/common/statistics.h"
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/estimation/scene_graph.h"

#include <cstdint>
#include <string>
#include <vector>

namespace geofusion {

struct RunResults {
  std::string method;
  std::string source;     ///< the recording
  std::string model_set;  ///< name of the model set
  /// The effective configuration the run was made with (YAML of config/config.h's loader).
  std::string config_yaml;
  double recording_duration_s = 0.0;
  double wall_time_s = 0.0;  ///< processing time of the whole run
  double peak_rss_mb = 0.0;  ///< the process's peak resident memory at the end (0: unknown)
  int frames_seen = 0;       ///< synchronised RGB-D + detection sets
  int frames_skipped = 0;    ///< ... of which dropped (the sum of frames_dropped)
  /// Inputs not used, by reason (FrameDrop's and SkipReason's words): frames and detections.
  std::vector<std::pair<std::string, std::size_t>> frames_dropped, detections_dropped;
  int keyframes_over_budget = 0;  ///< keyframes longer than input.keyframe_budget_ms
  /// The background map's insertions and their CPU time (`background` in the file; absent when
  /// the run made no background).
  bool has_background = false;
  BackgroundStats background;
  std::vector<KeyframeResult> keyframes;
  KeyframeResult final_map;    ///< after SceneEstimator::finish()
  SupportPlane support_plane;  ///< the estimator's table plane (map frame), when it found one
  /// The final map's support graph as a plan (scene_graph.h; `final_map.scene_graph` in the
  /// file), with its stability check's verdicts; written when has_scene_graph, not read back.
  bool has_scene_graph = false;
  SupportGraph scene_graph;
  std::vector<double> trajectory_stamps;
  std::vector<Eigen::Isometry3d> trajectory;  ///< final estimate of T_map_cam per keyframe
  /// A saved map (map_store.h): its id, the background file it belongs to (name beside the YAML,
  /// size, FNV-1a 64 checksum in hex; empty: none) and the last map -> odom correction.
  std::string map_id;
  /// ... who saved it (the node's launch id: an autosave is resumed only by the launch that
  /// wrote it; empty: unknown), how many keyframes the map had seen in all (resumed ones
  /// included) and the next object id (a resumed map never gives an id out twice).
  std::string session;
  int keyframes_total = 0;
  int next_object_id = 0;
  std::string background_file, background_checksum;
  std::uint64_t background_bytes = 0;
  Eigen::Isometry3d T_map_odom = Eigen::Isometry3d::Identity();
};

/// Objects removed over the run's keyframes by reason (RemovalReason's words, zeros included).
std::vector<std::pair<std::string, std::size_t>> removalsByReason(const RunResults& results);
/// Keyframes whose relocalisation searched, by decision (applied, no_gain, beyond_drift,
/// ambiguous; zeros included).
std::vector<std::pair<std::string, std::size_t>> relocalisationsByDecision(
    const RunResults& results);

/// Optimisation stages (keyframes and the final map) whose solve failed, their result not used.
int failedStages(const RunResults& results);

/// Writes the results YAML atomically (temporary file, then rename).
bool writeRunResults(const std::string& path, const RunResults& results, std::string* error);

/// Reads a results YAML back (the evaluator's input). Object classes are looked up in `models`
/// (an unknown class fails); contacts get indices into their objects again. The support plane
/// comes back with its normal and height only.
bool readRunResults(const std::string& path, const ModelSet& models, RunResults* results,
                    std::string* error);

}  // namespace geofusion
