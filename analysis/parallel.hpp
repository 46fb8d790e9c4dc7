// Internal: a minimal work-sharing loop for the analysis kernels (no pool: the callers run a
// handful of large tasks, so starting a thread per call costs nothing measurable).
#pragma once
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace rig::analysis::detail {

// Runs `fn(i)` for i in [0, count) over `threads` threads (dynamic assignment).
// The first exception (e.g. a source that ends early) stops the others and is rethrown here.
template <class Fn>
void parallel_for(std::size_t count, unsigned threads, Fn&& fn) {
  std::atomic<std::size_t> next{0};
  std::exception_ptr err;
  std::mutex err_mutex;
  auto work = [&] {
    for (std::size_t i; (i = next.fetch_add(1)) < count;) try {
        fn(i);
      } catch (...) {
        std::lock_guard lock(err_mutex);
        if (!err) err = std::current_exception();
        next = count;
      }
  };
  {
    std::vector<std::jthread> pool;
    for (unsigned t = 1; t < threads && t < count; ++t) pool.emplace_back(work);
    work();
  }
  if (err) std::rethrow_exception(err);
}

}  // namespace rig::analysis::detail
