// Internal: a minimal work-sharing loop for the analysis kernels (no pool: the callers run a
// handful of large tasks, so starting a thread per call costs nothing measurable).
#pragma once
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>
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

// Workers kept for a series of short parallel loops: the noise-model fit runs some twenty loops
// of 31 small subset fits each (about 0.1-0.3 ms a loop), where starting a thread per loop, as
// parallel_for does, would cost a third of what the second core gains. run() uses the calling
// thread and the workers, and returns when every index is done; the work of index i must not
// depend on which thread runs it, so the results are the same whatever the thread count.
class WorkTeam {
 public:
  explicit WorkTeam(unsigned threads) {
    for (unsigned t = 1; t < threads; ++t) workers_.emplace_back([this] { serve(); });
  }
  ~WorkTeam() {
    {
      std::lock_guard lk(mu_);
      stop_ = true;
    }
    wake_.notify_all();
  }  // workers_ (declared last) join first
  WorkTeam(const WorkTeam&) = delete;
  WorkTeam& operator=(const WorkTeam&) = delete;

  // Runs fn(i) for i in [0, count); the first exception stops the others and is rethrown here.
  void run(std::size_t count, const std::function<void(std::size_t)>& fn) {
    if (workers_.empty() || count < 2) {
      for (std::size_t i = 0; i < count; ++i) fn(i);
      return;
    }
    {
      std::lock_guard lk(mu_);
      job_ = &fn;
      count_ = count;
      next_ = 0;
      busy_ = workers_.size();
      ++generation_;
    }
    wake_.notify_all();
    work();
    std::unique_lock lk(mu_);
    done_.wait(lk, [&] { return busy_ == 0; });
    job_ = nullptr;
    if (err_) std::rethrow_exception(std::exchange(err_, nullptr));
  }

 private:
  void work() {
    for (std::size_t i; (i = next_.fetch_add(1)) < count_;) try {
        (*job_)(i);
      } catch (...) {
        std::lock_guard lk(mu_);
        if (!err_) err_ = std::current_exception();
        next_ = count_;
      }
  }
  void serve() {
    std::uint64_t seen = 0;
    for (;;) {
      {
        std::unique_lock lk(mu_);
        wake_.wait(lk, [&] { return stop_ || generation_ != seen; });
        if (stop_) return;
        seen = generation_;
      }
      work();
      std::lock_guard lk(mu_);
      if (--busy_ == 0) done_.notify_one();
    }
  }

  std::mutex mu_;
  std::condition_variable wake_, done_;
  const std::function<void(std::size_t)>* job_ = nullptr;
  std::size_t count_ = 0, busy_ = 0;
  std::atomic<std::size_t> next_{0};
  std::uint64_t generation_ = 0;
  bool stop_ = false;
  std::exception_ptr err_;
  std::vector<std::jthread> workers_;
};

}  // namespace rig::analysis::detail
