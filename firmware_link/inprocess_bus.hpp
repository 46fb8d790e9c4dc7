// An in-process CAN bus with the same CanTransport interface as SocketCAN: every
// frame a port sends is delivered to every other port whose filters accept it
// (vcan semantics: no echo to the sender). Used by host tests and by the
// in-process emulated plant.
// Lockstep (Options::lockstep): as in PX4's simulator, the simulation's transport owns
// simulated time. Frames are stamped with the SimClock's time, and a receive(timeout)
// that finds nothing queued advances the clock by `timeout` -- stepping the world, whose
// firmware emulator puts the frames on the bus -- instead of waiting. The rig's client
// then has one path for real and simulated time: it only ever calls receive(timeout).
#pragma once
#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "firmware_link/can_transport.hpp"
#include "rig/core/clock.hpp"

namespace rig::link {

class InProcessPort;

// A port's receive queue: a FIFO on one vector that keeps its capacity. std::deque allocated and
// freed a node every few frames (an RxFrame is about 100 bytes, a node 512), a cost the lockstep
// profile showed at 13.7 million frames per paper run.
class FrameFifo {
 public:
  std::size_t size() const { return v_.size() - head_; }
  bool empty() const { return head_ == v_.size(); }
  void push_back(const RxFrame& f) { v_.push_back(f); }
  // Aggregate-built (clang 14 has no parenthesised aggregate initialisation for emplace_back).
  void emplace_back(const CanFrame& f, double t_s) { v_.push_back(RxFrame{f, t_s, std::nullopt}); }
  const RxFrame& front() const { return v_[head_]; }
  void pop_front() {
    if (++head_ == v_.size()) {  // drained: start over in the same storage
      v_.clear();
      head_ = 0;
    } else if (head_ >= kCompactAfter && 2 * head_ >= v_.size()) {  // never drained: drop the read half
      v_.erase(v_.begin(), v_.begin() + static_cast<std::ptrdiff_t>(head_));
      head_ = 0;
    }
  }

 private:
  static constexpr std::size_t kCompactAfter = 4096;
  std::vector<RxFrame> v_;
  std::size_t head_ = 0;  // the first frame not yet taken
};

class InProcessBus : public std::enable_shared_from_this<InProcessBus> {
 public:
  struct Options {
    std::string name = "bus0";
    // Per-port receive queue, frames. A real socket drops when its buffer is
    // full; so does this (counted in TransportStats::rx_dropped).
    std::size_t rx_capacity = std::size_t{1} << 20;
    // Set: the bus runs in lockstep on this clock (see above); it must outlive the bus.
    // Unset: wall time, receive() blocks (timestamps on the steady clock).
    SimClock* lockstep = nullptr;
  };
  static std::shared_ptr<InProcessBus> create(Options opts);
  static std::shared_ptr<InProcessBus> create() { return create(Options{}); }

  // A new node on the bus; the port keeps the bus alive.
  std::unique_ptr<CanTransport> open(const std::string& port_name);
  // Delivers a frame to every port as if a third node (or the controller, for
  // error frames) had put it on the bus.
  void inject(const CanFrame& f);
  const std::string& name() const { return opts_.name; }
  double now() const;  // the bus's time: the SimClock's in lockstep, else the steady clock

 private:
  friend class InProcessPort;
  explicit InProcessBus(Options opts) : opts_(std::move(opts)) {}
  void deliver(const CanFrame& f, const InProcessPort* from) { deliver(std::span(&f, 1), from); }
  // One lock of the bus and one of each receiving port per batch, not per frame; the frames
  // of a batch share one timestamp (in lockstep the simulated time cannot move during a send).
  void deliver(std::span<const CanFrame> frames, const InProcessPort* from);
  void deliver_fd(const RxFrame& f, const InProcessPort* from);  // one CAN FD frame (f.fd set)
  void detach(InProcessPort* p);

  Options opts_;
  std::mutex mu_;  // guards ports_
  std::vector<InProcessPort*> ports_;
};

class InProcessPort final : public CanTransport {
 public:
  ~InProcessPort() override;
  void send(const CanFrame& f) override { send_batch(std::span(&f, 1)); }
  void send_batch(std::span<const CanFrame> frames) override;
  void send_fd(const CanFdFrame& f) override;  // the in-process bus carries CAN FD frames too
  std::optional<RxFrame> receive(double timeout_s, const CancelToken& cancel) override;
  std::size_t receive_batch(std::vector<RxFrame>& out, std::size_t max, double timeout_s,
                            const CancelToken& cancel) override;
  double now_s() const override { return bus_->now(); }
  void set_filters(std::span<const CanFilter> filters) override;
  TransportStats stats() const override;
  std::string name() const override;

 private:
  friend class InProcessBus;
  InProcessPort(std::shared_ptr<InProcessBus> bus, std::string name) : bus_(std::move(bus)), name_(std::move(name)) {}
  void push(std::span<const CanFrame> frames, double t_s);  // called by the bus
  void push_fd(const RxFrame& f);                            // called by the bus
  std::size_t take_all_locked(std::vector<RxFrame>& out, std::size_t max);  // mu_ held
  std::optional<RxFrame> take_locked();  // the next data frame queued, if any (mu_ held)
  std::optional<RxFrame> receive_lockstep(double timeout_s, const CancelToken& cancel);

  std::shared_ptr<InProcessBus> bus_;
  std::string name_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  FrameFifo queue_;
  // queue_.size(), written under mu_: a lockstep poll of an empty queue (the firmware's command
  // poll every tick) reads it instead of taking mu_. A frame pushed by another thread just
  // after the read is seen by the next poll, as it would be had the poll locked first.
  std::atomic<std::size_t> queued_{0};
  std::vector<CanFilter> filters_;
  TransportStats stats_;  // tx aside: it is tx_
  // Frames sent: a counter of its own, so that a send takes no lock of this port (the sender's
  // count needs no ordering with the receive queue that mu_ guards).
  std::atomic<uint64_t> tx_{0};
};

}  // namespace rig::link
