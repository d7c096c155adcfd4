// Every node's configuration from the one loader (config/config.h): the file of the private
// parameter ~params_file, then the launch files' explicit choices (~method, ~model_set,
// ~models_dir, when set), checked the same way. An error (unreadable file, bad
// value, unknown choice) throws std::runtime_error naming the key: the node refuses to start.
// Unknown keys, and private parameters that no setting reads (an old flat parameter file
// loaded with rosparam, a typo), are warned about with the nearest known key. The effective
// configuration is printed once (what differs from the defaults at INFO, everything at DEBUG), the
// file's warnings kept in ~config_warnings; the node publishes ~effective_config once it runs
// with it (publishEffectiveConfig).
#pragma once

#include "geofusion/config/config.h"
#include "geofusion/model/object_model.h"

#include <dynamic_reconfigure/Config.h>
#include <ros/ros.h>

#include <string>
#include <vector>

namespace geofusion {

/// The configuration of the node whose private handle is `pnh`. `extra_params`: further private
/// parameters the node reads itself (not warned about).
GeoFusionConfig loadNodeConfig(const ros::NodeHandle& pnh,
                               const std::vector<std::string>& extra_params = {});

/// ~effective_config: the configuration the node runs with, as YAML. Set last in a node's
/// constructor (and after a reconfigure), so that a reader sees the node as configured.
void publishEffectiveConfig(const ros::NodeHandle& pnh, const GeoFusionConfig& config);

/// Sets every reconfigurable setting's value from `config` in a dynamic_reconfigure state (e.g. one
/// from the generated config's __toMessage__); returns the message's names no setting has.
std::vector<std::string> fillReconfigure(const GeoFusionConfig& config,
                                         dynamic_reconfigure::Config* message);

/// Applies a dynamic_reconfigure state to `config` through the loader's checks (the .cfg names map
/// to settings by Setting::reconfigure_name); returns the problems, one sentence each.
std::vector<std::string> applyReconfigure(const dynamic_reconfigure::Config& message,
                                          GeoFusionConfig* config);

/// The model set of model_set.name / model_set.dir. Throws std::runtime_error naming the set and
/// the reasons when it does not load (the node refuses to start); classes left out are warned.
ModelSet loadNodeModelSet(const GeoFusionConfig& config);

/// The path of the geofusion package (for the model-set table), or "" when ROS cannot find it.
std::string packageDir();

}  // namespace geofusion
