#include "geofusion/common/time_jump.h"

#include <algorithm>

namespace geofusion {

TimeJumpGate::TimeJumpGate(std::size_t inputs, double tolerance_s, double join_timeout_s)
    : tolerance_s_(tolerance_s),
      join_timeout_s_(join_timeout_s),
      last_stamp_(inputs, 0.0),
      joined_(inputs, true) {}

TimeJumpGate::Decision TimeJumpGate::onMessage(std::size_t index, double stamp_s, double wall_s) {
  Decision d;
  if (index >= last_stamp_.size() || !(stamp_s > 0.0)) return d;  // no stamp: no time to judge
  const bool back = last_stamp_[index] > 0.0 && stamp_s + tolerance_s_ < last_stamp_[index];
  if (!joined_[index]) {
    // Waiting for this input's first message after the jump: the new epoch's messages are
    // stamped near where the jump went; those from before it are dropped.
    if (back || stamp_s <= jump_to_s_ + tolerance_s_ ||
        wall_s - jumped_at_wall_s_ > join_timeout_s_) {
      joined_[index] = true;
      last_stamp_[index] = stamp_s;
    } else {
      d.keep = false;
    }
    return d;
  }
  // Back against this input's own last stamp but not against the others' (its own late
  // message from before the jump, let through by the timeout): no new epoch.
  double others = 0.0;
  for (std::size_t j = 0; j < last_stamp_.size(); ++j)
    if (j != index && joined_[j]) others = std::max(others, last_stamp_[j]);
  if (back && !(stamp_s + tolerance_s_ < others)) {
    last_stamp_[index] = stamp_s;
    return d;
  }
  if (back) {
    d.jumped = true;
    d.from_s = *std::max_element(last_stamp_.begin(), last_stamp_.end());
    ++jumps_;
    jumped_at_wall_s_ = wall_s;
    jump_to_s_ = stamp_s;
    std::fill(joined_.begin(), joined_.end(), false);
    joined_[index] = true;
  }
  last_stamp_[index] = std::max(back ? 0.0 : last_stamp_[index], stamp_s);
  return d;
}

}  // namespace geofusion
