#include "geofusion/ros/node_config.h"

#include <ros/package.h>

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

namespace geofusion {
namespace {

// Launch-file choices that override the file: private parameter -> setting.
const std::vector<std::pair<std::string, std::string>>& launchOverrides() {
  static const std::vector<std::pair<std::string, std::string>> overrides{
      {"method", "method"},
      {"model_set", "model_set.name"},
      {"models_dir", "model_set.dir"},
      {"autosave_prefix", "node.autosave_prefix"}};
  return overrides;
}

// Private parameters read outside the loader: the robot file's names, the node's own.
bool readElsewhere(const std::string& name, const std::vector<std::string>& extra) {
  static const std::vector<std::string> known{
      "params_file",       "effective_config",  "config_warnings",  "rgb_topic", "depth_topic",
      "camera_info_topic", "detections_topic",  "wheel_odom_topic", "map_frame", "odom_frame",
      "base_frame",        "camera_link_frame", "camera_frame"};
  if (std::find(known.begin(), known.end(), name) != known.end()) return true;
  if (std::find(extra.begin(), extra.end(), name) != extra.end()) return true;
  for (const auto& o : launchOverrides())
    if (o.first == name) return true;
  // A dynamic_reconfigure name set before the node starts is a user's (the server writes its
  // values only once running): it belongs in the file, where it is read and checked.
  return false;
}

// Private parameters no setting reads, with the nearest known key.
void warnUnreadParams(const ros::NodeHandle& pnh, const std::vector<std::string>& extra) {
  std::vector<std::string> names;
  if (!ros::param::getParamNames(names)) return;
  const std::string prefix = pnh.getNamespace() + "/";
  for (const std::string& full : names) {
    if (full.rfind(prefix, 0) != 0) continue;
    const std::string name = full.substr(prefix.size());
    const std::string top = name.substr(0, name.find('/'));
    if (readElsewhere(top, extra)) continue;
    const std::string nearest = nearestSettingKey(name);
    ROS_WARN_STREAM("geofusion: parameter " << full << " is not read by anything"
                                            << (nearest.empty() ? ""
                                                                : "; did you mean " + nearest +
                                                                      " in the file of "
                                                                      "~params_file?"));
  }
}

}  // namespace

std::vector<std::string> fillReconfigure(const GeoFusionConfig& config,
                                         dynamic_reconfigure::Config* message) {
  std::vector<std::string> unknown;
  for (auto& d : message->doubles) {
    const Setting* s = findReconfigurable(d.name);
    if (s)
      d.value = configNumber(*s, config);
    else
      unknown.push_back(d.name);
  }
  for (auto& i : message->ints) {
    const Setting* s = findReconfigurable(i.name);
    if (s)
      i.value = static_cast<int>(configNumber(*s, config));
    else
      unknown.push_back(i.name);
  }
  return unknown;
}

std::vector<std::string> applyReconfigure(const dynamic_reconfigure::Config& message,
                                          GeoFusionConfig* config) {
  std::vector<std::string> problems;
  auto apply = [&](const std::string& name, double value) {
    const Setting* s = findReconfigurable(name);
    std::string error;
    if (!s) {
      problems.push_back(name + ": no setting of that name");
    } else if (!setConfigNumber(*s, value, config, &error)) {
      problems.push_back(error + " (kept " + s->valueText(*config) + ")");
    }
  };
  for (const auto& d : message.doubles) apply(d.name, d.value);
  for (const auto& i : message.ints) apply(i.name, i.value);
  return problems;
}

std::string packageDir() {
  // Without a sourced workspace rospack only prints errors: say nothing here, the caller says
  // what to do (requirePackageDir).
  const char* path = std::getenv("ROS_PACKAGE_PATH");
  if (!path || !*path) return "";
  return ros::package::getPath("geofusion");
}

ModelSet loadNodeModelSet(const GeoFusionConfig& config) {
  ModelSet models;
  std::vector<std::string> errors;
  if (!loadModelSet(config.model_set.name, config.model_set.dir, packageDir(), &models, &errors,
                    config.model_set.surface_features)) {
    std::string all;
    for (const auto& e : errors) all += "\n  " + e;
    throw std::runtime_error("model_set.name: cannot load the model set '" + config.model_set.name +
                             "', not starting:" + all);
  }
  for (const auto& e : errors) ROS_WARN_STREAM("geofusion: " << e);
  return models;
}

GeoFusionConfig loadNodeConfig(const ros::NodeHandle& pnh,
                               const std::vector<std::string>& extra_params) {
  GeoFusionConfig config;
  ConfigReport report;
  std::string params_file;
  pnh.param<std::string>("params_file", params_file, "");
  if (!params_file.empty()) loadConfigFile(params_file, &config, &report);
  for (const auto& [param, key] : launchOverrides()) {
    std::string value;
    if (!pnh.getParam(param, value)) continue;
    std::string error;
    if (!setConfigValue(key, value, &config, &error))
      report.errors.push_back("~" + param + " (launch argument): " + error);
  }
  for (const std::string& w : report.warnings) ROS_WARN_STREAM("geofusion: " << w);
  pnh.setParam("config_warnings", report.warnings);  // for users and tools that start it
  if (!report.ok()) {
    std::string all;
    for (const std::string& e : report.errors) all += "\n  " + e;
    throw std::runtime_error("bad configuration, not starting:" + all);
  }
  warnUnreadParams(pnh, extra_params);
  ROS_INFO_STREAM("geofusion: configuration "
                  << (params_file.empty() ? "(no ~params_file)" : "from " + params_file)
                  << ", what differs from the defaults:\n"
                  << configDiff(config));
  ROS_DEBUG_STREAM("geofusion: the whole effective configuration:\n" << configYaml(config));
  return config;
}

void publishEffectiveConfig(const ros::NodeHandle& pnh, const GeoFusionConfig& config) {
  pnh.setParam("effective_config", configYaml(config));
}

}  // namespace geofusion
