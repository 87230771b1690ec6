#include "host/interrupt.hpp"

#include <pthread.h>
#include <signal.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstring>
#include <mutex>
#include <thread>

namespace talus {

namespace {

// the signal that asked to stop (0: none); see the header for why it is process-wide
std::atomic<int> g_requested{0};

// SIGINT and SIGTERM, but not one the process started with ignored (a job a shell put in the
// background ignores SIGINT): that one stays ignored
sigset_t interrupt_signals() {
  sigset_t set;
  sigemptyset(&set);
  for (const int signal : {SIGINT, SIGTERM}) {
    struct sigaction old {};
    if (sigaction(signal, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    sigaddset(&set, signal);
  }
  return set;
}

// one request may arrive twice at once: `timeout` (coreutils) and schedulers signal the process
// and then its whole process group, so a second signal within this time [s] is the same request;
// a person's second Ctrl-C comes later
constexpr double kSameRequest = 1.0;

// the watching thread: the first signal marks the process, a second one later kills it as the
// default action would have
void watch(sigset_t set) {
  std::chrono::steady_clock::time_point first;
  for (;;) {
    int signal = 0;
    if (sigwait(&set, &signal) != 0) continue;
    int none = 0;
    if (g_requested.compare_exchange_strong(none, signal)) {
      first = std::chrono::steady_clock::now();
      continue;
    }
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - first).count() <
        kSameRequest)
      continue;
    std::signal(signal, SIG_DFL);
    sigset_t one;
    sigemptyset(&one);
    sigaddset(&one, signal);
    pthread_sigmask(SIG_UNBLOCK, &one, nullptr);
    raise(signal);
  }
}

}  // namespace

Interrupted::Interrupted(int signal, const std::string& where)
    : Error(std::string("interrupted by ") +
            (signal == SIGINT    ? "SIGINT"
             : signal == SIGTERM ? "SIGTERM"
                                 : strsignal(signal)) +
            " during " + where),
      signal_(signal) {}

void watch_interrupts() {
  static std::once_flag once;
  std::call_once(once, [] {
    const sigset_t set = interrupt_signals();
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    std::thread(watch, set).detach();
  });
}

int interrupt_requested() { return g_requested.load(std::memory_order_relaxed); }

void throw_if_interrupted(const std::string& where) {
  if (const int signal = interrupt_requested()) throw Interrupted(signal, where);
}

}  // namespace talus
