// Progress of long runs on stderr: one line redrawn in place on a terminal, a line every few
// seconds otherwise (CI logs), silent when disabled.
#pragma once
#include <chrono>
#include <string>

namespace talus {

class Progress {
 public:
  Progress(std::string label, double total, bool enabled = true);
  // reports `done` out of `total` (e.g. simulated seconds), with an optional note; throws
  // talus::Interrupted when the process was asked to stop (host/interrupt.hpp), enabled or not
  void update(double done, const std::string& note = "");
  void finish(const std::string& note = "");

 private:
  std::string label_;
  double total_;
  bool enabled_;
  bool tty_;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace talus
