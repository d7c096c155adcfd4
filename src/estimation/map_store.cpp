#include "geofusion/estimation/map_store.h"

#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

namespace geofusion {

namespace {

std::function<void(const char*)>& saveHook() {
  static std::function<void(const char*)> hook;
  return hook;
}

void step(const char* name) {
  if (saveHook()) saveHook()(name);
}

std::string newMapId() {
  std::random_device device;
  const auto now = std::chrono::system_clock::now().time_since_epoch().count();
  std::mt19937_64 rng(static_cast<std::uint64_t>(now) ^ device());
  char id[17];
  std::snprintf(id, sizeof(id), "%016llx", static_cast<unsigned long long>(rng()));
  return id;
}

std::string prefixOf(const std::string& path) {
  const std::string ext = ".yaml";
  if (path.size() > ext.size() && path.compare(path.size() - ext.size(), ext.size(), ext) == 0)
    return path.substr(0, path.size() - ext.size());
  return path;
}

// Removes what saves of this prefix left that the current YAML does not name: backgrounds of
// other maps (<prefix>.<16 hex>.bt) and temporary files. `keep` is the current background's file
// name ("" : none).
void removeStale(const std::string& prefix, const std::string& keep) {
  namespace fs = std::filesystem;
  const fs::path base(prefix);
  const fs::path dir = base.has_parent_path() ? base.parent_path() : fs::path(".");
  const std::string stem = base.filename().string();
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.compare(0, stem.size() + 1, stem + ".") != 0) continue;
    const std::string rest = name.substr(stem.size() + 1);
    const bool old_background =
        rest.size() == 16 + 3 && rest.compare(16, 3, ".bt") == 0 && name != keep;
    const bool temporary =
        rest == "yaml.tmp" || (rest.size() == 16 + 7 && rest.compare(16, 7, ".bt.tmp") == 0);
    if (old_background || temporary) fs::remove(e.path(), ec);
  }
}

}  // namespace

void setSaveMapHook(std::function<void(const char* step)> hook) {
  saveHook() = std::move(hook);
}

std::string fileChecksum(const std::string& path, std::uint64_t* bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "";
  std::uint64_t h = 1469598103934665603ull, n = 0;
  char buffer[65536];
  while (in.read(buffer, sizeof(buffer)) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i) {
      h ^= static_cast<unsigned char>(buffer[i]);
      h *= 1099511628211ull;
    }
    n += static_cast<std::uint64_t>(in.gcount());
  }
  if (bytes) *bytes = n;
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

bool saveMap(const std::string& prefix, RunResults results,
             const BackgroundWriter& write_background, MapFiles* files, std::string* error) {
  if (prefix.empty()) {
    if (error) *error = "empty path";
    return false;
  }
  results.map_id = newMapId();
  const std::string stem = std::filesystem::path(prefix).filename().string();
  MapFiles out;
  out.yaml = prefix + ".yaml";
  results.background_file.clear();
  if (write_background) {
    results.background_file = stem + "." + results.map_id + ".bt";
    out.background = prefix + "." + results.map_id + ".bt";
    step("background");
    if (!write_background(out.background, error)) return false;
    results.background_checksum = fileChecksum(out.background, &results.background_bytes);
    if (results.background_checksum.empty()) {
      if (error) *error = "cannot read back " + out.background;
      std::remove(out.background.c_str());
      return false;
    }
  }
  step("yaml");
  if (!writeRunResults(out.yaml, results, error)) {
    if (!out.background.empty()) std::remove(out.background.c_str());
    return false;
  }
  step("cleanup");
  removeStale(prefix, results.background_file);
  if (files) *files = out;
  return true;
}

bool loadMap(const std::string& path, const ModelSet& models, RunResults* results, MapFiles* files,
             std::string* error) {
  const std::string prefix = prefixOf(path);
  MapFiles found;
  found.yaml = prefix + ".yaml";
  RunResults r;
  if (!readRunResults(found.yaml, models, &r, error)) return false;
  if (r.map_id.empty()) {
    if (error)
      *error = found.yaml +
               " is a results file, not a saved map (no `map:` block; save_map "
               "writes one)";
    return false;
  }
  if (!r.background_file.empty()) {
    const std::filesystem::path dir = std::filesystem::path(found.yaml).parent_path();
    found.background = (dir / r.background_file).string();
    std::uint64_t bytes = 0;
    const std::string checksum = fileChecksum(found.background, &bytes);
    if (checksum.empty()) {
      if (error) *error = found.yaml + " names the background " + found.background + ", missing";
      return false;
    }
    if (checksum != r.background_checksum || bytes != r.background_bytes) {
      if (error)
        *error = found.background + " is not the background saved with " + found.yaml +
                 " (size or checksum differ): the pieces do not belong together";
      return false;
    }
  }
  removeStale(prefix, r.background_file);
  *results = std::move(r);
  if (files) *files = found;
  return true;
}

bool readSavedMapSession(const std::string& path, std::string* session, bool* exists,
                         std::string* error) {
  const std::string yaml = prefixOf(path) + ".yaml";
  std::error_code ec;
  *exists = std::filesystem::exists(yaml, ec);
  if (!*exists) {
    if (error) *error = "no saved map at " + yaml;
    return false;
  }
  try {
    const YAML::Node map = YAML::LoadFile(yaml)["map"];
    if (!map || !map.IsMap()) {
      if (error) *error = yaml + " is not a saved map (no `map:` block)";
      return false;
    }
    *session = map["session"].as<std::string>("");
    return true;
  } catch (const std::exception& e) {
    if (error) *error = yaml + ": " + e.what();
    return false;
  }
}

}  // namespace geofusion
