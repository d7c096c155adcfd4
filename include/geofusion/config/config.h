// The one configuration of GeoFusion: every setting of every runtime module in one nested YAML
// file (config/geofusion.yaml is the commented template), read by one loader into the modules'
// Config structs. The nodes, the nodelets, run_offline, the benchmark and the tests all use it.
// The loader checks the type and range of every key (an error names the file, the key and what is
// allowed), warns about unknown keys with the nearest known one ("eps_fb: unknown, did you mean
// association.eps_fp?"), and prints the effective configuration (whole, or what differs from the
// defaults) so that every result says how it was made.
#pragma once

#include "geofusion/background/background_map.h"
#include "geofusion/common/ingestion.h"
#include "geofusion/estimation/frame_by_frame.h"
#include "geofusion/estimation/keyframe_selector.h"
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/estimation/scene_graph.h"
#include "geofusion/model/surface_features.h"
#include "geofusion/odometry/visual_odometry.h"
#include "geofusion/physics/stability.h"

#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace geofusion {

/// The synchronised inputs and the checks of each incoming frame and detection.
struct InputConfig {
  int queue_size = 10;  ///< messages queued per synchroniser input
  /// Synchronised frames waiting for the estimator's thread (the node): a frame arriving when
  /// this many wait pushes the oldest out, counted as a queue overflow.
  int frame_queue_size = 5;
  double sync_max_interval_s = 0.05;   ///< largest stamp spread of a synchronised set
  double stale_after_s = 3.0;          ///< watchdog: an input silent this long is reported
  double sync_timeout_s = 3.0;         ///< ... all arriving but never synchronised this long
  double time_jump_tolerance_s = 1.0;  ///< stamps going back more: a looping bag, a restart
  double tf_timeout_s = 0.1;           ///< wall-clock wait for the camera pose in TF
  double warn_period_s = 5.0;          ///< throttle of repeated warnings
};

/// What only the ROS node does with the map (plain data: the core never reads it).
struct NodeConfig {
  bool publish_map_to_odom = true;  ///< broadcast map -> odom at every keyframe
  std::string save_on_shutdown;     ///< save the map to this path prefix at shutdown ("": no)
  /// Autosave (docs/running.md): the map saved as ~save_map does every N keyframes or T seconds
  /// (whichever comes first, on a keyframe; both 0: off), under this prefix ("": $ROS_HOME/
  /// geofusion/<node name>/autosave); resumed at start when the same launch wrote it.
  int autosave_every_keyframes = 10;
  double autosave_every_s = 60.0;
  std::string autosave_prefix;
  bool resume_autosave = true;
  int background_publish_every = 5;  ///< publish the background every N keyframes
  /// Every object of the map as a TF frame <object_frame_prefix><id> under the map frame, at
  /// every keyframe; a removed object's frame is no longer sent.
  bool publish_object_frames = true;
  std::string object_frame_prefix = "object_";
  /// The last keyframe's object frames are sent again at this rate (0: only at keyframes),
  /// stamped object_frames_tolerance_s ahead of the current time (as amcl's transform_tolerance),
  /// so that robot code can look them up at ros::Time::now().
  double object_frames_rate_hz = 10.0;
  double object_frames_tolerance_s = 0.2;
  /// The background's colour in rviz: "height" (a bluish grey, lighter with height) or "grey".
  std::string background_colour = "height";
};

/// Detections from vision_msgs/Detection3DArray (the adapter nodelet and run_offline): which
/// model-set class a detector's class id stands for (plain data: the core never reads it).
struct VisionMsgsConfig {
  /// "" : each id is the model-set class with that id; else "id: class_name, ..." pairs.
  std::string class_map;
};

/// Where the object models come from: a name of the model-set table (primitives, ycb_video) or
/// the path of a model-set YAML, with its meshes' folder.
struct ModelSetConfig {
  std::string name = "primitives";
  std::string dir;  ///< meshes ("": beside the YAML; ycb_video: $GEOFUSION_YCB_DIR)
  SurfaceFeatureConfig surface_features;
};

struct GeoFusionConfig {
  /// The method of the paper's comparison (geofusion, rfront, bslam, fbf); estimator.method
  /// follows it.
  std::string method = "geofusion";
  ModelSetConfig model_set;
  InputConfig input;
  IngestionConfig ingestion;
  FrameByFrame::Config checks;
  KeyframeSelectorConfig keyframes;
  EstimatorConfig estimator;
  bool background_enabled = true;
  /// The support graph as a plan: "over" without a contact (scene_graph.h).
  SupportGraphConfig scene_graph;
  BackgroundMapConfig background;
  VisualOdometryConfig visual_odometry;
  NodeConfig node;
  VisionMsgsConfig vision_msgs;
};

/// One setting: its key in the YAML file (dotted path), type, allowed values, documentation and
/// whether dynamic_reconfigure may change it while running (then under `reconfigure_name` in
/// cfg/SceneEstimator.cfg).
struct Setting {
  enum class Type { kDouble, kInt, kBool, kString, kVector3 };
  std::string key;
  Type type = Type::kDouble;
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  std::vector<std::string> choices;  ///< strings: the allowed values (empty: any)
  std::string doc;                   ///< what it is, with its unit
  std::string reconfigure_name;      ///< "": fixed at start
  std::function<void*(GeoFusionConfig&)> field;

  /// The value in `config` as YAML text (strings quoted when needed, vectors as [x, y, z]).
  std::string valueText(const GeoFusionConfig& config) const;
  /// "[0.001, 0.5]", "one of fbf, bslam, rfront, geofusion", "true or false", ...
  std::string allowed() const;
};

/// Every setting, in the order of the template file.
const std::vector<Setting>& settings();
const Setting* findSetting(const std::string& key);
/// The reconfigurable setting of a dynamic_reconfigure name, or null.
const Setting* findReconfigurable(const std::string& reconfigure_name);

/// The known key nearest to `key` ("" when none is near): the same last part first (a flat
/// "eps_fp" means association.eps_fp), else the smallest edit distance.
std::string nearestSettingKey(const std::string& key);

/// Problems found while loading; the configuration is usable only without errors.
struct ConfigReport {
  std::vector<std::string> errors;    ///< bad type, out of range, unknown choice, unreadable file
  std::vector<std::string> warnings;  ///< unknown keys, with the nearest known key
  bool ok() const { return errors.empty(); }
};

/// Reads `path` over `config` (keys not in the file keep their value). False on any error.
bool loadConfigFile(const std::string& path, GeoFusionConfig* config, ConfigReport* report);
/// The same from YAML text; `source` names it in messages.
bool loadConfigText(const std::string& text, const std::string& source, GeoFusionConfig* config,
                    ConfigReport* report);

/// Sets one setting from its text (as in YAML), with the loader's checks. For command-line
/// overrides (--set key=value) and dynamic_reconfigure.
bool setConfigValue(const std::string& key, const std::string& value, GeoFusionConfig* config,
                    std::string* error);
/// A number into a numeric setting (range-checked).
bool setConfigNumber(const Setting& setting, double value, GeoFusionConfig* config,
                     std::string* error);
double configNumber(const Setting& setting, const GeoFusionConfig& config);

/// The effective configuration as YAML: every setting (with its documentation as comments when
/// `comments`), or only those that differ from the defaults (`changed_only`); only the top-level
/// `sections` given (empty: all).
std::string configYaml(const GeoFusionConfig& config, bool changed_only = false,
                       bool comments = false, const std::vector<std::string>& sections = {});
/// One line a changed setting, "key: value (default d)"; "defaults" when nothing changed.
std::string configDiff(const GeoFusionConfig& config);

}  // namespace geofusion
