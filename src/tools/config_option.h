// The tools' configuration options: --params FILE (the one configuration's YAML) and
// --set KEY=VALUE (any setting, in the order given), plus shorthands a tool may add
// (run_offline's --method, --models, ...). Applied through the loader's checks; every problem is
// said on stderr with the tool's name.
#pragma once

#include "command_line.h"
#include "geofusion/config/config.h"

#include <iostream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace geofusion {

struct ConfigOptions {
  std::string params;  ///< the configuration file
  /// (key, value) overrides in the order given: --set and the shorthands.
  std::vector<std::pair<std::string, std::string>> overrides;

  /// Declares --params and --set on `args`.
  void declare(CommandLine* args) {
    args->value("--params", &params);
    args->custom("--set", [this](const std::string& v) {
      const std::size_t eq = v.find('=');
      if (eq == std::string::npos) throw std::runtime_error("--set expects KEY=VALUE, got " + v);
      overrides.emplace_back(v.substr(0, eq), v.substr(eq + 1));
    });
  }
  /// Declares `flag` VALUE as a shorthand for --set key=VALUE.
  void shorthand(CommandLine* args, const std::string& flag, const std::string& key) {
    args->custom(flag, [this, key](const std::string& v) { overrides.emplace_back(key, v); });
  }
  /// The file, then the overrides, over `config`; warnings and errors on stderr. False on any
  /// error.
  bool apply(const std::string& tool, GeoFusionConfig* config) const {
    ConfigReport report;
    if (!params.empty()) loadConfigFile(params, config, &report);
    for (const auto& [key, value] : overrides) {
      std::string error;
      if (!setConfigValue(key, value, config, &error))
        report.errors.push_back("command line: " + error);
    }
    for (const std::string& w : report.warnings) std::cerr << tool << ": warning: " << w << "\n";
    for (const std::string& e : report.errors) std::cerr << tool << ": " << e << "\n";
    return report.ok();
  }
};

}  // namespace geofusion
