#include "rig/gpio/line_rig_io.hpp"

#include <pthread.h>
#include <sched.h>

#include "rig/core/errors.hpp"

namespace rig::gpio {

namespace {
Output lamp_output(Lamp l) {
  switch (l) {
    case Lamp::Ready: return Output::LampReady;
    case Lamp::Running: return Output::LampRunning;
    case Lamp::Pass: return Output::LampPass;
    case Lamp::Fail: return Output::LampFail;
  }
  return Output::LampFail;
}
}  // namespace

LineRigIo::LineRigIo(std::unique_ptr<LineDriver> driver) : drv_(std::move(driver)) {
  {
    std::lock_guard lk(drv_mu_);
    drv_->set(Output::Power, false);  // a fresh rig starts with the DUT unpowered
    estop_ = drv_->estop_active();
  }
  thread_ = std::thread([this] { watch(); });
}

LineRigIo::~LineRigIo() {
  stop_ = true;
  drv_->wake();  // the watcher would otherwise sleep out its 50 ms wait before it sees stop_
  if (thread_.joinable()) thread_.join();
  try {
    std::lock_guard lk(drv_mu_);
    drv_->set(Output::Power, false);  // leaving the rig: DUT unpowered
  } catch (...) {
  }
}

void LineRigIo::watch() {
  // The e-stop path must not queue behind the rig's other threads (stream
  // reader, recorder, analysis): run it real-time when allowed (root or
  // CAP_SYS_NICE); otherwise it stays a normal thread that only sleeps in poll.
  sched_param sp{};
  sp.sched_priority = std::min(sched_get_priority_max(SCHED_FIFO), 80);
  realtime_ = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0;
  using clk = std::chrono::steady_clock;
  while (!stop_) {
    std::optional<bool> edge;
    try {
      edge = drv_->wait_estop_edge(std::chrono::milliseconds(50));
    } catch (const std::exception&) {
      // A line that can no longer be read is treated like a pressed e-stop.
      edge = true;
    }
    if (!edge) continue;
    if (!*edge) {
      estop_ = false;
      continue;
    }
    const auto t0 = clk::now();
    {
      std::lock_guard lk(drv_mu_);  // hard safety first: power off before anything else runs
      try {
        drv_->set(Output::Power, false);
      } catch (...) {
      }
      power_ = false;
      estop_ = true;
    }
    const auto edge_t = drv_->last_edge_time().value_or(t0);
    reaction_s_ = std::chrono::duration<double>(clk::now() - edge_t).count();
    std::function<void()> h;
    {
      std::lock_guard lk(handler_mu_);
      h = handler_;
    }
    if (h) {
      try {
        h();
      } catch (...) {  // the handler's failure must not kill the watcher
      }
    }
  }
}

void LineRigIo::set_dut_power(bool on) {
  std::lock_guard lk(drv_mu_);
  if (on && (estop_ || drv_->estop_active())) {
    estop_ = true;
    throw HardwareError("DUT power on refused: e-stop/interlock is active (" + drv_->describe() + ")");
  }
  drv_->set(Output::Power, on);
  power_ = on;
}

void LineRigIo::set_lamp(Lamp lamp, bool on) {
  const Output o = lamp_output(lamp);
  std::lock_guard lk(drv_mu_);
  if (drv_->has(o)) drv_->set(o, on);  // lamps not wired in the config are ignored
}

void LineRigIo::on_estop(std::function<void()> handler) {
  std::lock_guard lk(handler_mu_);
  handler_ = std::move(handler);
}

std::string LineRigIo::describe() const {
  return drv_->describe() + (realtime_ ? " (e-stop watch SCHED_FIFO)" : "");
}

// ---- SimLines ----

void SimLines::set(Output o, bool active) {
  std::lock_guard lk(mu_);
  out_[static_cast<int>(o)] = active;
  static const char* names[kOutputs] = {"power", "lamp_ready", "lamp_running", "lamp_pass", "lamp_fail"};
  log_.push_back(std::string(names[static_cast<int>(o)]) + "=" + (active ? "1" : "0"));
}

bool SimLines::estop_active() {
  std::lock_guard lk(mu_);
  return estop_;
}

std::optional<bool> SimLines::wait_estop_edge(std::chrono::milliseconds timeout) {
  std::unique_lock lk(mu_);
  ++waits_;  // the reader is back: whatever it took before is handled
  handled_cv_.notify_all();
  if (!cv_.wait_for(lk, timeout, [this] { return !edges_.empty() || woken_; }) || edges_.empty()) return std::nullopt;
  const bool v = edges_.front();
  edges_.erase(edges_.begin());
  ++taken_;
  waits_at_take_ = waits_;
  return v;
}

void SimLines::wake() {
  {
    std::lock_guard lk(mu_);
    woken_ = true;
  }
  cv_.notify_all();
}

bool SimLines::push_edge_locked(bool active) {
  if (estop_ == active) return false;  // no edge
  estop_ = active;
  edges_.push_back(active);
  log_.push_back(std::string("estop=") + (active ? "1" : "0"));
  return true;
}

void SimLines::drive_estop(bool active) {
  {
    std::lock_guard lk(mu_);
    if (!push_edge_locked(active)) return;
  }
  cv_.notify_all();
}

void SimLines::drive_estop_handled(bool active) {
  std::unique_lock lk(mu_);
  if (!push_edge_locked(active)) return;
  const uint64_t ours = taken_ + edges_.size();  // edges taken once this one is
  cv_.notify_all();
  if (!handled_cv_.wait_for(lk, std::chrono::seconds(10), [&] { return taken_ >= ours && waits_ > waits_at_take_; }))
    throw HardwareError("simulated e-stop edge not handled by the rig's GPIO logic within 10 s");
}

bool SimLines::level(Output o) const {
  std::lock_guard lk(mu_);
  return out_[static_cast<int>(o)];
}

void SimLines::note(const std::string& what) {
  std::lock_guard lk(mu_);
  log_.push_back(what);
}

std::vector<std::string> SimLines::log() const {
  std::lock_guard lk(mu_);
  return log_;
}

}  // namespace rig::gpio
