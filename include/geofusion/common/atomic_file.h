// Writing a file so that no reader ever sees half of it, even after a power loss: write
// `<path>.tmp`, flush it to the disk (fsync), rename it over `path`, then flush the directory so
// that the rename itself is on the disk. Private to the core.
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <string>

namespace geofusion {

/// fsync() of a file or directory opened read-only; false when it cannot be opened or synced.
inline bool syncToDisk(const std::string& path, bool directory = false) {
  const int fd = ::open(path.c_str(), O_RDONLY | (directory ? O_DIRECTORY : 0));
  if (fd < 0) return false;
  const bool ok = ::fsync(fd) == 0;
  ::close(fd);
  return ok;
}

/// The directory holding `path` ("." for a bare file name).
inline std::string directoryOf(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

/// Calls write(tmp_path) and, when it succeeds, syncs the temporary file, renames it to `path`
/// and syncs the directory.
inline bool writeFileAtomically(const std::string& path,
                                const std::function<bool(const std::string&)>& write,
                                std::string* error) {
  const std::string tmp = path + ".tmp";
  // The system's reason (no space left, read-only file system, ...) when it gave one.
  const auto fail = [&](const std::string& what) {
    const int code = errno;
    std::remove(tmp.c_str());
    if (error) *error = what + (code != 0 ? std::string(": ") + std::strerror(code) : "");
    return false;
  };
  errno = 0;
  if (!write(tmp)) return fail("cannot write " + tmp);
  errno = 0;
  if (!syncToDisk(tmp)) return fail("cannot flush " + tmp + " to the disk");
  errno = 0;
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
    return fail("cannot rename " + tmp + " to " + path);
  errno = 0;
  if (!syncToDisk(directoryOf(path), true))
    return fail("cannot flush the directory of " + path + " to the disk");
  return true;
}

/// writeFileAtomically of a text.
inline bool writeTextAtomically(const std::string& path, const std::string& text,
                                std::string* error) {
  return writeFileAtomically(
      path,
      [&text](const std::string& tmp) {
        std::ofstream f(tmp);
        f << text;
        return static_cast<bool>(f.flush());
      },
      error);
}

}  // namespace geofusion
