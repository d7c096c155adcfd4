// Writing a file so that no reader ever sees half of it: write `<path>.tmp`, then rename it over
// `path`. Private to the core.
#pragma once

#include <cstdio>
#include <functional>
#include <string>

namespace geofusion {

/// Calls write(tmp_path) and, when it succeeds, renames the temporary file to `path`.
inline bool writeFileAtomically(const std::string& path,
                                const std::function<bool(const std::string&)>& write,
                                std::string* error) {
  const std::string tmp = path + ".tmp";
  if (!write(tmp)) {
    std::remove(tmp.c_str());
    if (error) *error = "cannot write " + tmp;
    return false;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    if (error) *error = "cannot rename " + tmp + " to " + path;
    return false;
  }
  return true;
}

}  // namespace geofusion
