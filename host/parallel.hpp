// Independent tasks on the host's cores: the diagnosis's many short simulations of the machine
// alone (sim2real/diagnose), each its own WheelLoader, direct solver and effects.
//
// Design: the caller names the tasks by index and keeps their results in its own vector, indexed
// the same way, so what it reads afterwards does not depend on which thread ran what or when: a
// loop run on several threads gives the bits the same loop gives on one. A task that throws does
// not stop the others; once all have run, the exception of the lowest index is rethrown, the one
// a serial loop would have met first (the serial loop would not have run the later tasks, which
// is why only tasks without side effects outside their own result belong here).
#pragma once
#include <cstddef>
#include <functional>

namespace talus {

// the host's hardware threads, at least 1
int hardware_threads();

// task(0) .. task(n - 1) on up to `threads` threads (the caller's among them; 1: a plain loop on
// the caller's thread), returning when all have run; see above for exceptions
void parallel_for(std::size_t n, int threads, const std::function<void(std::size_t)>& task);

}  // namespace talus
