#include "host/progress.hpp"

#include <unistd.h>

#include <cstdio>

#include "host/interrupt.hpp"

namespace talus {

namespace {
// a new line at most this often when stderr is not a terminal [s]
constexpr double kLogInterval = 5.0;
// redraw interval on a terminal [s]
constexpr double kTtyInterval = 0.2;
}  // namespace

Progress::Progress(std::string label, double total, bool enabled)
    : label_(std::move(label)), total_(total), enabled_(enabled), tty_(isatty(fileno(stderr)) != 0),
      start_(std::chrono::steady_clock::now()), last_(start_) {}

void Progress::update(double done, const std::string& note) {
  // a long loop's natural point to stop at when asked (host/interrupt.hpp)
  if (interrupt_requested()) {
    // how far it had come: of its total when it knows one (soil tests and cuts run to a
    // criterion, not to a total)
    char where[160];
    if (total_ > 0.0)
      std::snprintf(where, sizeof where, "%s at %.3g of %.3g", label_.c_str(), done, total_);
    else
      std::snprintf(where, sizeof where, "%s at %.3g", label_.c_str(), done);
    throw_if_interrupted(where);
  }
  if (!enabled_) return;
  auto now = std::chrono::steady_clock::now();
  double since = std::chrono::duration<double>(now - last_).count();
  if (since < (tty_ ? kTtyInterval : kLogInterval)) return;
  last_ = now;
  double elapsed = std::chrono::duration<double>(now - start_).count();
  double frac = total_ > 0 ? done / total_ : 0.0;
  double eta = frac > 0 ? elapsed * (1.0 - frac) / frac : 0.0;
  const int width = 24;
  int filled = static_cast<int>(frac * width + 0.5);
  std::string bar(filled, '#');
  bar.resize(width, '.');
  std::fprintf(stderr, "%s%s [%s] %3.0f%%  %.0f s elapsed, ~%.0f s left  %s%s", tty_ ? "\r" : "",
               label_.c_str(), bar.c_str(), 100.0 * frac, elapsed, eta, note.c_str(),
               tty_ ? "\033[K" : "\n");
  std::fflush(stderr);
}

void Progress::finish(const std::string& note) {
  if (!enabled_) return;
  double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "%s%s done in %.1f s  %s%s\n", tty_ ? "\r" : "", label_.c_str(), elapsed,
               note.c_str(), tty_ ? "\033[K" : "");
}

}  // namespace talus
