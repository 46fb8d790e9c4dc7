#include "firmware_link/inprocess_bus.hpp"

#include <algorithm>
#include <chrono>
#include <optional>

#include "rig/core/errors.hpp"

namespace rig::link {

// ---- bus ----

std::shared_ptr<InProcessBus> InProcessBus::create(Options opts) {
  return std::shared_ptr<InProcessBus>(new InProcessBus(std::move(opts)));
}

std::unique_ptr<CanTransport> InProcessBus::open(const std::string& port_name) {
  std::unique_ptr<InProcessPort> p(new InProcessPort(shared_from_this(), port_name));
  std::lock_guard lk(mu_);
  ports_.push_back(p.get());
  return p;
}

double InProcessBus::now() const {
  if (opts_.lockstep) return opts_.lockstep->now_s();
  using namespace std::chrono;
  return duration<double>(steady_clock::now().time_since_epoch()).count();
}

void InProcessBus::inject(const CanFrame& f) { deliver(f, nullptr); }

void InProcessBus::deliver(std::span<const CanFrame> frames, const InProcessPort* from) {
  if (frames.empty()) return;
  const double t = now();
  std::lock_guard lk(mu_);
  for (InProcessPort* p : ports_)
    if (p != from) p->push(frames, t);
}

void InProcessBus::deliver_fd(const RxFrame& f, const InProcessPort* from) {
  RxFrame rx = f;
  rx.t_s = now();
  std::lock_guard lk(mu_);
  for (InProcessPort* p : ports_)
    if (p != from) p->push_fd(rx);
}

void InProcessBus::detach(InProcessPort* p) {
  std::lock_guard lk(mu_);
  ports_.erase(std::remove(ports_.begin(), ports_.end(), p), ports_.end());
}

// ---- port ----

InProcessPort::~InProcessPort() { bus_->detach(this); }

void InProcessPort::push(std::span<const CanFrame> frames, double t_s) {
  bool queued = false;
  {
    std::lock_guard lk(mu_);
    for (const CanFrame& f : frames) {
      if (!filter_accepts(filters_, f)) continue;
      if (queue_.size() >= bus_->opts_.rx_capacity) {
        ++stats_.rx_dropped;
        continue;
      }
      queue_.emplace_back(f, t_s);
      queued = true;
    }
    queued_.store(queue_.size(), std::memory_order_release);
  }
  if (queued) cv_.notify_one();
}

void InProcessPort::push_fd(const RxFrame& f) {
  {
    std::lock_guard lk(mu_);
    // An FD frame is filtered on its identifier, as the kernel does.
    CanFrame head;
    head.id = f.fd->id;
    head.extended = f.fd->extended;
    if (!filter_accepts(filters_, head)) return;
    if (queue_.size() >= bus_->opts_.rx_capacity) {
      ++stats_.rx_dropped;
      return;
    }
    queue_.push_back(f);
    queued_.store(queue_.size(), std::memory_order_release);
  }
  cv_.notify_one();
}

void InProcessPort::send_fd(const CanFdFrame& f) {
  if (f.len > 64 || canfd_round_up(f.len) != f.len)
    throw HardwareError(name() + ": CAN FD frame of " + std::to_string(f.len) + " bytes");
  tx_.fetch_add(1, std::memory_order_relaxed);
  RxFrame rx;
  rx.fd = f;
  rx.fd->fd = true;
  bus_->deliver_fd(rx, this);
}

void InProcessPort::send_batch(std::span<const CanFrame> frames) {
  // As frame-by-frame sends would: the frames before a bad one go out, then the error.
  const auto bad = std::find_if(frames.begin(), frames.end(), [](const CanFrame& f) { return f.len > 8; });
  const auto good = frames.first(static_cast<std::size_t>(bad - frames.begin()));
  if (!good.empty()) {
    tx_.fetch_add(good.size(), std::memory_order_relaxed);
    bus_->deliver(good, this);
  }
  if (bad != frames.end())
    throw HardwareError(name() + ": frame 0x" + std::to_string(bad->id) + " longer than 8 bytes");
}

std::optional<RxFrame> InProcessPort::take_locked() {
  while (!queue_.empty()) {
    RxFrame f = queue_.front();
    queue_.pop_front();
    queued_.store(queue_.size(), std::memory_order_relaxed);
    if (f.frame.error) {
      ++stats_.error_frames;
      const ErrorFrameInfo e = classify_error_frame(f.frame);
      if (e.fatal) throw HardwareError(name() + ": CAN " + e.text);
      continue;  // warnings are counted, not fatal
    }
    ++stats_.rx;
    return f;
  }
  return std::nullopt;
}

std::size_t InProcessPort::take_all_locked(std::vector<RxFrame>& out, std::size_t max) {
  // As take_locked() frame by frame, but each frame copied once, from the queue into `out`
  // (an RxFrame is about 110 bytes and a paper run moves 13.7 million of them).
  std::size_t n = 0;
  while (n < max && !queue_.empty()) {
    const RxFrame& f = queue_.front();
    if (f.frame.error) {
      const CanFrame err = f.frame;
      queue_.pop_front();
      queued_.store(queue_.size(), std::memory_order_relaxed);
      ++stats_.error_frames;
      const ErrorFrameInfo e = classify_error_frame(err);
      if (e.fatal) throw HardwareError(name() + ": CAN " + e.text);
      continue;  // warnings are counted, not fatal
    }
    out.push_back(f);
    queue_.pop_front();
    ++stats_.rx;
    ++n;
  }
  queued_.store(queue_.size(), std::memory_order_relaxed);
  return n;
}

std::size_t InProcessPort::receive_batch(std::vector<RxFrame>& out, std::size_t max, double timeout_s,
                                         const CancelToken& cancel) {
  // Wall time: frame by frame (the base class), as a socket would be read.
  if (!bus_->opts_.lockstep) return CanTransport::receive_batch(out, max, timeout_s, cancel);
  // Lockstep: as receive_lockstep() below, but everything queued under one lock.
  auto poll = [&]() -> std::size_t {
    cancel.throw_if_requested();
    if (queued_.load(std::memory_order_acquire) == 0) return 0;
    std::lock_guard lk(mu_);
    return take_all_locked(out, max);
  };
  if (max == 0) return 0;
  if (const std::size_t n = poll()) return n;
  if (timeout_s <= 0) return 0;
  bus_->opts_.lockstep->sleep_for(timeout_s, cancel);
  return poll();
}

std::optional<RxFrame> InProcessPort::receive_lockstep(double timeout_s, const CancelToken& cancel) {
  auto poll = [&]() -> std::optional<RxFrame> {
    cancel.throw_if_requested();
    if (queued_.load(std::memory_order_acquire) == 0) return std::nullopt;
    std::lock_guard lk(mu_);
    return take_locked();
  };
  if (auto f = poll()) return f;
  if (timeout_s <= 0) return std::nullopt;
  // Nothing queued: let the simulated time pass. The lock is not held: stepping the world
  // makes the firmware emulator send, and its frames land in this queue.
  bus_->opts_.lockstep->sleep_for(timeout_s, cancel);
  return poll();
}

std::optional<RxFrame> InProcessPort::receive(double timeout_s, const CancelToken& cancel) {
  if (bus_->opts_.lockstep) return receive_lockstep(timeout_s, cancel);
  using clock = std::chrono::steady_clock;
  // The deadline is read off the wall clock only when the queue is empty: the frames are
  // often already queued.
  std::optional<clock::time_point> deadline;
  std::unique_lock lk(mu_);
  for (;;) {
    cancel.throw_if_requested();
    if (auto f = take_locked()) return f;
    if (timeout_s <= 0) return std::nullopt;
    const auto now = clock::now();
    if (!deadline) deadline = now + std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(timeout_s));
    if (now >= *deadline) return std::nullopt;
    // Wake at least every 20 ms to notice cancellation.
    cv_.wait_until(lk, std::min(*deadline, now + std::chrono::milliseconds(20)));
  }
}

void InProcessPort::set_filters(std::span<const CanFilter> filters) {
  std::lock_guard lk(mu_);
  filters_.assign(filters.begin(), filters.end());
}

TransportStats InProcessPort::stats() const {
  std::lock_guard lk(mu_);
  TransportStats s = stats_;
  s.tx = tx_.load(std::memory_order_relaxed);
  return s;
}

std::string InProcessPort::name() const { return "inprocess:" + bus_->name() + "/" + name_; }

}  // namespace rig::link
