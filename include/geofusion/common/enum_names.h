// Words for enums in results files and diagnostics: one table of (value, word) pairs per enum,
// read both ways by these two helpers.
#pragma once

#include <cstddef>
#include <string>
#include <utility>

namespace geofusion {

/// The word of `value` in `names` (the first entry's when it is not listed).
template <typename E, std::size_t N>
const char* nameIn(const std::pair<E, const char*> (&names)[N], E value) {
  for (const auto& n : names)
    if (n.first == value) return n.second;
  return names[0].second;
}

/// The value whose word is `name`; false (value untouched) when none is.
template <typename E, std::size_t N>
bool parseIn(const std::pair<E, const char*> (&names)[N], const std::string& name, E* value) {
  for (const auto& n : names) {
    if (name == n.second) {
      *value = n.first;
      return true;
    }
  }
  return false;
}

}  // namespace geofusion
