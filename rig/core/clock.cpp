#include "rig/core/clock.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <thread>

namespace rig {

namespace {
double steady_s() {
  using namespace std::chrono;
  return duration<double>(steady_clock::now().time_since_epoch()).count();
}
}  // namespace

RealClock::RealClock() : t0_(steady_s()) {}

double RealClock::now_s() const { return steady_s() - t0_; }

void RealClock::sleep_for(double dt_s, const CancelToken& cancel) {
  const double end = now_s() + dt_s;
  for (;;) {
    cancel.throw_if_requested();
    const double left = end - now_s();
    if (left <= 0) return;
    std::this_thread::sleep_for(std::chrono::duration<double>(std::min(left, 0.02)));
  }
}

void SimClock::sleep_for(double dt_s, const CancelToken& cancel) {
  cancel.throw_if_requested();
  if (dt_s <= 0) return;
  // The world is stepped in slices so that a cancellation (an e-stop edge in an
  // emulated run) lands within 10 ms of simulated time.
  constexpr double kSlice = 0.01;
  double left = dt_s;
  while (left > 1e-12) {
    const double dt = std::min(kSlice, left);
    if (advance_) advance_(dt);
    t_ += dt;
    left -= dt;
    cancel.throw_if_requested();
  }
}

std::string iso8601_utc_now() { return iso8601_utc(std::time(nullptr)); }

std::string iso8601_utc(std::time_t t) {
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

}  // namespace rig
