// Which ground-truth keyframe a keyframe of the results is: the evaluation and the BOP dataset
// writer match them by stamp.
#pragma once

#include "geofusion/simulation/dataset.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace geofusion {

// The ground-truth keyframe of a results stamp: the nearest within the tolerance, or null.
class KeyframeMatcher {
 public:
  KeyframeMatcher(const GroundTruth& gt, double tolerance_s) : tolerance_s_(tolerance_s) {
    for (const GroundTruthFrame& f : gt.frames)
      if (f.keyframe) keyframes_.push_back(&f);
  }
  const GroundTruthFrame* at(double stamp) const {
    auto it = std::lower_bound(keyframes_.begin(), keyframes_.end(), stamp,
                               [](const GroundTruthFrame* f, double s) { return f->stamp_s < s; });
    const GroundTruthFrame* best = nullptr;
    for (auto c : {it, it == keyframes_.begin() ? it : it - 1}) {
      if (c == keyframes_.end()) continue;
      if (std::abs((*c)->stamp_s - stamp) <= tolerance_s_ &&
          (!best || std::abs((*c)->stamp_s - stamp) < std::abs(best->stamp_s - stamp)))
        best = *c;
    }
    return best;
  }

 private:
  double tolerance_s_;
  std::vector<const GroundTruthFrame*> keyframes_;
};

}  // namespace geofusion
