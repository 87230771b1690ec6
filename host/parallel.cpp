#include "host/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <thread>
#include <vector>

namespace talus {

int hardware_threads() {
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

void parallel_for(std::size_t n, int threads, const std::function<void(std::size_t)>& task) {
  // every task's exception, kept by index
  std::vector<std::exception_ptr> errors(n);
  std::atomic<std::size_t> next{0};
  const auto work = [&] {
    for (std::size_t i = next++; i < n; i = next++) {
      try {
        task(i);
      } catch (...) {
        errors[i] = std::current_exception();
      }
    }
  };
  // the caller works too: threads - 1 helpers, none for a single task
  const std::size_t helpers =
      std::min(n, static_cast<std::size_t>(std::max(1, threads))) - (n > 0 ? 1 : 0);
  std::vector<std::thread> pool;
  pool.reserve(helpers);
  for (std::size_t k = 0; k < helpers; ++k) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  // the first failure in index order
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
}

}  // namespace talus
