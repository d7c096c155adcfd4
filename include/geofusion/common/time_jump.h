#pragma once
// Time jumps of a set of synchronised inputs (a looping bag, a restarted driver): the first input
// whose stamp goes back by more than the tolerance starts a new epoch (the caller restarts its
// synchroniser and resets what it keeps); each other input joins the new epoch with its own first
// message stamped back. Until it has, an input's messages are from before the jump (the old loop's
// last messages still in flight) and are dropped, so that they neither reach the new synchroniser
// nor start a second jump that would lose the new epoch's first set. An input that has not jumped
// back within `join_timeout_s` (wall time) is let through again; a message that goes back
// against its own input only (that input's late message from before the jump) starts no new
// epoch. Messages without a stamp (0) are passed on unjudged. ROS-free (tested in
// test/common/test_time_jump.cpp).

#include <cstddef>
#include <vector>

namespace geofusion {

class TimeJumpGate {
 public:
  struct Decision {
    bool keep = true;     ///< feed the message to the synchroniser
    bool jumped = false;  ///< this message started a new epoch: restart, then feed it
    double from_s = 0.0;  ///< jumped: the newest stamp before the jump
  };
  TimeJumpGate(std::size_t inputs, double tolerance_s, double join_timeout_s = 2.0);
  /// A message of input `index` stamped `stamp_s`, received at wall time `wall_s`.
  Decision onMessage(std::size_t index, double stamp_s, double wall_s);
  /// Epochs started so far (jumps seen).
  int jumps() const { return jumps_; }

 private:
  double tolerance_s_, join_timeout_s_;
  std::vector<double> last_stamp_;  ///< per input, its newest stamp in its epoch (0: none yet)
  std::vector<bool> joined_;        ///< per input: it has a message of the current epoch
  double jumped_at_wall_s_ = 0.0;
  double jump_to_s_ = 0.0;
  int jumps_ = 0;
};

}  // namespace geofusion
