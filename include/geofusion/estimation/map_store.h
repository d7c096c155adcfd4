// A saved map as one unit. <prefix>.yaml (the results file: objects, contacts, trajectory, support
// plane, map -> odom; docs/results.md) is the commit point: it names the background OctoMap it
// belongs to, <prefix>.<map id>.bt, with its size and checksum. Saving writes the background under
// its new name first, then the YAML through a rename, then removes the previous background, so a
// kill at any moment leaves the old map or the new one whole, never a new YAML with an old
// background. What a killed save had written (a .tmp, a background no YAML names) is removed by
// the next save or load of the same prefix. ROS-free; the background is written and read by the
// caller's functions (BackgroundMap::writeBinary / readBinary), so that this file knows no
// OctoMap.
#pragma once

#include "geofusion/estimation/run_results.h"

#include <functional>
#include <string>

namespace geofusion {

struct MapFiles {
  std::string yaml;        ///< <prefix>.yaml
  std::string background;  ///< <prefix>.<map id>.bt; empty when the map has none
};

/// Writes the background to the path it is given; false with `error` on failure.
using BackgroundWriter = std::function<bool(const std::string& path, std::string* error)>;

/// Saves `results` (its map_id and background fields are filled here) and, when
/// `write_background` is set, the background, as one unit under `prefix`.
bool saveMap(const std::string& prefix, RunResults results,
             const BackgroundWriter& write_background, MapFiles* files, std::string* error);

/// Loads the map saved under `path` (the prefix, or its .yaml). Fails when the background the
/// YAML names is missing or is not the one saved with it (size, checksum). `files` says where
/// the pieces are.
bool loadMap(const std::string& path, const ModelSet& models, RunResults* results, MapFiles* files,
             std::string* error);

/// Who saved the map under `path` (RunResults::session) without loading it: false with `error`
/// when there is no saved map there or it cannot be read; `exists` says whether the YAML is there.
bool readSavedMapSession(const std::string& path, std::string* session, bool* exists,
                         std::string* error);

/// FNV-1a 64 of a file's bytes, 16 hex digits; empty when it cannot be read.
std::string fileChecksum(const std::string& path, std::uint64_t* bytes = nullptr);

/// Test hook: called with the name of each step of saveMap ("background", "yaml", "cleanup")
/// before it runs; a test kills the process there. Null (the default): nothing.
void setSaveMapHook(std::function<void(const char* step)> hook);

}  // namespace geofusion
