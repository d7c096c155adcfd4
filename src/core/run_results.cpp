#include "geofusion/core/run_results.h"

#include "yaml_io.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <fstream>

namespace geofusion {
namespace {

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
    out << YAML::Key << "support" << YAML::Value << c.support;
    out << YAML::Key << "distance_residual" << YAML::Value << c.distance_residual;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

void emitTimings(YAML::Emitter& out, const StageTimings& t) {
  out << YAML::Key << "timings_ms" << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "consistency" << YAML::Value << t.consistency_ms;
  out << YAML::Key << "association" << YAML::Value << t.association_ms;
  out << YAML::Key << "stage_one" << YAML::Value << t.stage_one_ms;
  out << YAML::Key << "relations" << YAML::Value << t.relations_ms;
  out << YAML::Key << "stage_two" << YAML::Value << t.stage_two_ms;
  out << YAML::Key << "total" << YAML::Value << t.total_ms << YAML::EndMap;
}

}  // namespace

bool writeRunResults(const std::string& path, const RunResults& r, std::string* error) {
  YAML::Emitter out;
  out.SetDoublePrecision(10);
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << "geofusion_results_v1";
  out << YAML::Key << "method" << YAML::Value << r.method;
  out << YAML::Key << "source" << YAML::Value << r.source;
  out << YAML::Key << "model_set" << YAML::Value << r.model_set;
  out << YAML::Key << "recording_duration_s" << YAML::Value << r.recording_duration_s;
  out << YAML::Key << "wall_time_s" << YAML::Value << r.wall_time_s;
  out << YAML::Key << "realtime_factor" << YAML::Value
      << (r.recording_duration_s > 0 ? r.wall_time_s / r.recording_duration_s : 0.0);
  out << YAML::Key << "frames_seen" << YAML::Value << r.frames_seen;
  out << YAML::Key << "frames_skipped" << YAML::Value << r.frames_skipped;
  out << YAML::Key << "keyframes" << YAML::Value << YAML::BeginSeq;
  for (const KeyframeResult& k : r.keyframes) {
    out << YAML::BeginMap;
    out << YAML::Key << "index" << YAML::Value << k.keyframe;
    char stamp[32];
    std::snprintf(stamp, sizeof(stamp), "%.9f", k.stamp_s);
    out << YAML::Key << "stamp" << YAML::Value << stamp;
    yaml_io::emitPose(out, "map_camera", k.T_map_cam);
    emitTimings(out, k.timings);
    out << YAML::Key << "removed_ids" << YAML::Value << YAML::Flow << k.removed_ids;
    emitObjects(out, k.objects, k.T_map_cam);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "final_map" << YAML::Value << YAML::BeginMap;
  emitTimings(out, r.final_map.timings);
  emitObjects(out, r.final_map.objects, r.final_map.T_map_cam);
  emitContacts(out, r.final_map);
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
  out << YAML::EndSeq << YAML::EndMap;
  return yaml_io::writeAtomically(
      path, "# GeoFusion run results (docs/results.md). Poses [x, y, z, qx, qy, qz, qw].\n", out,
      error);
}

}  // namespace geofusion
