#include "geofusion/common/input_monitor.h"

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <utility>

namespace geofusion {

namespace {
std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f s", s);
  return buf;
}
}  // namespace

InputMonitor::InputMonitor(std::vector<std::string> input_names, const Config& config, double now_s)
    : names_(std::move(input_names)), config_(config) {
  reset(now_s);
}

void InputMonitor::reset(double now_s) {
  start_s_ = now_s;
  inputs_.assign(names_.size(), InputState{});
  synchronized_count_ = 0;
  last_sync_s_ = now_s;
}

void InputMonitor::onMessage(std::size_t input_index, double now_s) {
  InputState& in = inputs_.at(input_index);
  if (in.count == 0) in.first_s = now_s;
  ++in.count;
  in.last_s = now_s;
}

void InputMonitor::onSynchronized(double now_s) {
  ++synchronized_count_;
  last_sync_s_ = now_s;
}

std::vector<std::string> InputMonitor::problems(double now_s) const {
  std::vector<std::string> out;
  bool all_fresh = true;
  double all_arriving_since = start_s_;
  for (std::size_t i = 0; i < names_.size(); ++i) {
    const InputState& in = inputs_[i];
    if (in.count == 0) {
      all_fresh = false;
      if (now_s - start_s_ > config_.stale_after_s) {
        out.push_back("no message received on " + names_[i] + " in " + seconds(now_s - start_s_));
      }
      continue;
    }
    all_arriving_since = std::max(all_arriving_since, in.first_s);
    if (now_s - in.last_s > config_.stale_after_s) {
      all_fresh = false;
      out.push_back("input " + names_[i] + " stopped: last message " + seconds(now_s - in.last_s) +
                    " ago (" + std::to_string(in.count) + " received)");
    }
  }
  if (!all_fresh) return out;

  // Every input is arriving. Have they been synchronising?
  const double since = std::max(all_arriving_since, last_sync_s_);
  if (now_s - since > config_.sync_timeout_s) {
    std::ostringstream os;
    os << (synchronized_count_ == 0 ? "inputs arrive but never synchronise"
                                    : "inputs arrive but stopped synchronising")
       << " for " << seconds(now_s - since) << ": ";
    for (std::size_t i = 0; i < names_.size(); ++i) {
      os << (i ? ", " : "") << names_[i] << " (" << inputs_[i].count << ")";
    }
    os << "; check that their header stamps match (detections must carry the RGB image's stamp)";
    out.push_back(os.str());
  }
  return out;
}

}  // namespace geofusion
