// Clock seam. Real: steady wall time. Simulated: time advances only when the
// consumer sleeps or reads samples, and advancing it steps the emulated plant
// (lockstep, like PX4 SIH), so a 110-minute procedure runs in seconds.
#pragma once
#include <ctime>
#include <functional>
#include <string>

#include "rig/core/cancel.hpp"

namespace rig {

class Clock {
 public:
  virtual ~Clock() = default;
  // Seconds since the clock's epoch (construction).
  virtual double now_s() const = 0;
  // Waits dt seconds (simulated: advances the plant by dt). Throws AbortedError
  // promptly when `cancel` is requested.
  virtual void sleep_for(double dt_s, const CancelToken& cancel) = 0;
};

// Wall-clock time; sleeps in slices of at most 20 ms so cancellation is prompt.
class RealClock final : public Clock {
 public:
  RealClock();
  double now_s() const override;
  void sleep_for(double dt_s, const CancelToken& cancel) override;

 private:
  double t0_;
};

// Simulated time. `advance` is called to move the world forward by dt seconds
// (the plant steps itself there); the clock's time moves by the same amount.
class SimClock final : public Clock {
 public:
  using Advance = std::function<void(double dt_s)>;
  explicit SimClock(Advance advance = {}) : advance_(std::move(advance)) {}
  void set_advance(Advance a) { advance_ = std::move(a); }
  double now_s() const override { return t_; }
  void sleep_for(double dt_s, const CancelToken& cancel) override;

 private:
  Advance advance_;
  double t_ = 0.0;
};

// ISO 8601 UTC wall time, e.g. "2026-11-22T05:30:12Z" (for passports and headers).
std::string iso8601_utc_now();
// The same form of a time in seconds since the epoch.
std::string iso8601_utc(std::time_t t);

}  // namespace rig
