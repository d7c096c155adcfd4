// Minimal command-line reading shared by the package's tools: flags in order, each flag's value.
#pragma once

#include <stdexcept>
#include <string>

namespace geofusion {

class CommandLine {
 public:
  CommandLine(int argc, char** argv) : argc_(argc), argv_(argv) {}
  /// The next argument (a flag), false at the end.
  bool next(std::string* flag) {
    if (i_ + 1 >= argc_) return false;
    flag_ = argv_[++i_];
    *flag = flag_;
    return true;
  }
  /// The value after the current flag; throws when there is none.
  std::string value() {
    if (i_ + 1 >= argc_) throw std::runtime_error("missing value after " + flag_);
    return argv_[++i_];
  }

 private:
  int argc_;
  char** argv_;
  int i_ = 0;
  std::string flag_;
};

}  // namespace geofusion
