// Interrupts (SIGINT from Ctrl-C, SIGTERM from a scheduler or `timeout`) as requests to stop
// between steps, so an interrupted command leaves its outputs as a killed one does, but says so
// and exits with 128 + the signal's number instead of dying mid-line.
//
// How: the command-line tool calls watch_interrupts() first thing, before any other thread
// exists (a thread started earlier keeps the signals unblocked, and one delivered there kills the
// process as before). It blocks both signals (PoCL's threads, started later, inherit the mask; a
// signal the process started with ignored stays ignored) and starts one thread that waits
// for them with sigwait: the first marks the process as interrupted, a second one more than a
// second later restores the default action and re-raises, so Ctrl-C twice still kills at once
// (one sooner is the same request: `timeout` signals the process and then its process group). Long
// loops poll between steps (Progress::update polls on every call, enabled or not; `talus run`'s
// loops poll every step) and unwind with talus::Interrupted, which the tool's main turns into one
// line and the exit code. A program that never calls watch_interrupts (an application embedding the
// library) keeps its own signal handling: nothing is ever marked and nothing thrown.
//
// The mark is process-wide state, the one mutable global of the library: a signal belongs to
// the process, not to an object.
#pragma once
#include <string>

#include "host/error.hpp"

namespace talus {

// the process was asked to stop; `what()` names the signal and where the command stood
class Interrupted : public Error {
 public:
  Interrupted(int signal, const std::string& where);
  int signal() const { return signal_; }
  // the conventional exit status: 128 + the signal's number (130 for SIGINT, 143 for SIGTERM)
  int exit_code() const { return 128 + signal_; }

 private:
  int signal_;
};

// blocks SIGINT and SIGTERM and starts the watching thread (once; later calls do nothing)
void watch_interrupts();

// the signal that asked the process to stop, or 0
int interrupt_requested();

// throws Interrupted naming `where` ("the dig at t = 3.2 s of 10 s") when a signal asked to stop
void throw_if_interrupted(const std::string& where);

}  // namespace talus
