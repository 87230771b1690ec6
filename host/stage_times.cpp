#include "host/stage_times.hpp"

#include <cstring>

#include "host/device.hpp"

namespace talus {

void StageTimes::charge(Clock::time_point now) {
  if (!open_.empty())
    totals_[open_.back()].second += std::chrono::duration<double>(now - mark_).count();
  mark_ = now;
}

size_t StageTimes::index_of(const char* name) {
  // a handful of stages: a linear search by name keeps the first-run order
  for (size_t k = 0; k < totals_.size(); ++k)
    if (std::strcmp(totals_[k].first.c_str(), name) == 0) return k;
  totals_.emplace_back(name, 0.0);
  return totals_.size() - 1;
}

void StageTimes::enter(const char* name) {
  charge(Clock::now());
  open_.push_back(index_of(name));
}

void StageTimes::leave() {
  charge(Clock::now());
  if (!open_.empty()) open_.pop_back();
}

void StageTimes::clear() {
  totals_.clear();
  open_.clear();
}

StageScope::StageScope(Device& dev, const char* name) : dev_(dev), times_(dev.stage_times()) {
  if (times_ == nullptr) return;
  dev_.finish();
  times_->enter(name);
}

StageScope::~StageScope() {
  if (times_ == nullptr) return;
  // a failed wait is not thrown from a destructor: the queue's next call reports it
  try {
    dev_.finish();
  } catch (const Error&) {
  }
  times_->leave();
}

}  // namespace talus
