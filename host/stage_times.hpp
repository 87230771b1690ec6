// Wall time per stage of a step: the cost breakdown of `talus bench dig` (issue 13).
//
// A run is profiled by giving its Device a StageTimes (Device::set_stage_times); the stages of
// the step mark themselves with a StageScope, which does nothing when no StageTimes is set, so an
// unprofiled run pays one pointer test per stage. While profiling, every stage boundary drains
// the queue: the device work a stage enqueued is charged to that stage, not to the next one that
// happens to wait for it. Those waits take the host-device overlap away, so a profiled step is a
// little slower than an unprofiled one; `talus bench dig` reports both.
//
// Stages nest. Each is charged its own time only: a stage that runs inside another (a direct
// solve inside the bucket-row setup) is subtracted from the outer one, so the totals add up to
// the wall time of the outermost stages.
#pragma once
#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace talus {

class Device;

class StageTimes {
 public:
  // a stage starts or ends now; the caller has drained the queue
  void enter(const char* name);
  void leave();
  // seconds per stage since construction or clear(), in the order the stages first ran
  const std::vector<std::pair<std::string, double>>& totals() const { return totals_; }
  void clear();

 private:
  using Clock = std::chrono::steady_clock;
  // charges the time since the last mark to the innermost open stage
  void charge(Clock::time_point now);
  size_t index_of(const char* name);

  std::vector<std::pair<std::string, double>> totals_;
  std::vector<size_t> open_;  // indices into totals_, innermost last
  Clock::time_point mark_;
};

// marks a stage for the lifetime of the scope when the device is being profiled
class StageScope {
 public:
  StageScope(Device& dev, const char* name);
  ~StageScope();
  StageScope(const StageScope&) = delete;
  StageScope& operator=(const StageScope&) = delete;

 private:
  Device& dev_;
  StageTimes* times_;
};

}  // namespace talus
