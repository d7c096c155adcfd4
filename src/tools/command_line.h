// Command-line reading shared by the package's tools: each tool declares its flags once (a
// value flag writes its parsed value, a switch sets a bool, a custom one runs a function), then
// parse() reads argv in order. Unknown flags, missing values and malformed numbers throw
// std::runtime_error naming the flag; -h / --help prints the tool's usage and exits 0.
#pragma once

#include <cstdlib>
#include <functional>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

namespace geofusion {

class CommandLine {
 public:
  void value(const std::string& flag, std::string* out) {
    takes_value_[flag] = [out](const std::string& v) { *out = v; };
  }
  void value(const std::string& flag, int* out) {
    takes_value_[flag] = [flag, out](const std::string& v) { *out = toNumber<int>(flag, v); };
  }
  void value(const std::string& flag, unsigned* out) {
    takes_value_[flag] = [flag, out](const std::string& v) {
      *out = static_cast<unsigned>(toNumber<long long>(flag, v));
    };
  }
  void value(const std::string& flag, double* out) {
    takes_value_[flag] = [flag, out](const std::string& v) { *out = toNumber<double>(flag, v); };
  }
  /// A flag with a value handled by `f` (e.g. a list to split).
  void custom(const std::string& flag, std::function<void(const std::string&)> f) {
    takes_value_[flag] = std::move(f);
  }
  /// A switch: its presence sets `*out` to `set_to`.
  void toggle(const std::string& flag, bool* out, bool set_to = true) {
    switches_[flag] = [out, set_to]() { *out = set_to; };
  }

  /// Reads argv[1..]; on -h / --help calls `usage` and exits with 0.
  void parse(int argc, char** argv, void (*usage)()) const {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "-h" || a == "--help") {
        usage();
        std::exit(0);
      }
      if (const auto s = switches_.find(a); s != switches_.end()) {
        s->second();
      } else if (const auto v = takes_value_.find(a); v != takes_value_.end()) {
        if (i + 1 >= argc) throw std::runtime_error("missing value after " + a);
        v->second(argv[++i]);
      } else {
        throw std::runtime_error("unknown option " + a);
      }
    }
  }

 private:
  template <typename T>
  static T toNumber(const std::string& flag, const std::string& v) {
    std::size_t used = 0;
    T x{};
    try {
      if constexpr (std::is_same_v<T, double>) {
        x = std::stod(v, &used);
      } else {
        x = static_cast<T>(std::stoll(v, &used));
      }
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != v.size())
      throw std::runtime_error(flag + " needs a number, not '" + v + "'");
    return x;
  }

  std::map<std::string, std::function<void(const std::string&)>> takes_value_;
  std::map<std::string, std::function<void()>> switches_;
};

/// Runs a tool's option parsing (`parse`, which throws std::exception on a bad option): false,
/// having printed "<tool>: <why>" and the usage, when the command line is wrong (exit code 2).
template <typename Parse>
bool readCommandLine(const char* tool, void (*usage)(), Parse&& parse) {
  try {
    parse();
    return true;
  } catch (const std::exception& e) {
    std::cerr << tool << ": " << e.what() << "\n";
    usage();
    return false;
  }
}

}  // namespace geofusion
