// CanTransport: what the rig-side client and the firmware emulator need from a
// CAN interface. Backends: SocketCAN on Asio (socketcan.hpp) and an in-process
// bus (inprocess_bus.hpp) for host tests and the in-process emulated plant.
#pragma once
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "firmware_link/protocol.hpp"
#include "rig/core/cancel.hpp"

namespace rig::link {

struct RxFrame {
  CanFrame frame;  // a classic frame (empty when `fd` holds a CAN FD frame)
  double t_s = 0;  // receive time on the transport's clock (CanTransport::now_s), seconds
  std::optional<CanFdFrame> fd;  // a CAN FD frame, from a transport that carries them
};

// Accept a frame when (frame.id & mask) == (id & mask), as SocketCAN's can_filter.
// Standard-id filters match standard frames only, extended-id filters extended ones.
struct CanFilter {
  uint32_t id = 0;
  uint32_t mask = 0;
  bool extended = false;
};

struct TransportStats {
  uint64_t tx = 0, rx = 0;
  uint64_t rx_dropped = 0;     // frames the receive queue had to drop (kernel SO_RXQ_OVFL / in-process capacity)
  uint64_t error_frames = 0;   // error frames seen (including the ones that only warn)
};

class CanTransport {
 public:
  virtual ~CanTransport() = default;
  // Throws HardwareError when the frame cannot be sent (interface down, bus-off).
  virtual void send(const CanFrame& f) = 0;
  // Sends a CAN FD frame (up to 64 bytes; DBC layouts with several samples per frame). A
  // transport or interface without CAN FD throws HardwareError saying so.
  virtual void send_fd(const CanFdFrame& f);
  // Sends the frames in order, as send() would one by one (stopping at the first that
  // throws). A backend may do it in one step: the in-process bus takes its locks once per
  // batch instead of once per frame (the emulated firmware sends each tick's frames so).
  virtual void send_batch(std::span<const CanFrame> frames) {
    for (const CanFrame& f : frames) send(f);
  }
  // Every frame queued now (at most `max`), appended to `out` in order, waiting up to
  // `timeout_s` for the first as receive() does; returns how many. Same errors as receive()
  // (the frames taken before the error stay in `out`). A backend may take them in one step
  // (the in-process bus: one lock per batch).
  virtual std::size_t receive_batch(std::vector<RxFrame>& out, std::size_t max, double timeout_s,
                                    const CancelToken& cancel) {
    std::size_t n = 0;
    for (double t = timeout_s; n < max; t = 0) {
      std::optional<RxFrame> f = receive(t, cancel);
      if (!f) break;
      out.push_back(*f);
      ++n;
    }
    return n;
  }
  // Next frame, or nullopt after `timeout_s` (0 = poll). Error frames that mean
  // the link is unusable (bus-off, error passive) throw HardwareError; warnings
  // are counted and skipped. Cancellation throws AbortedError.
  virtual std::optional<RxFrame> receive(double timeout_s, const CancelToken& cancel) = 0;
  // The clock RxFrame::t_s is read on (SocketCAN: the kernel's CLOCK_REALTIME stamps; the
  // in-process bus: its own time), so a client can tell how long ago a frame arrived.
  virtual double now_s() const = 0;
  // Replaces the receive filters (empty = receive everything).
  virtual void set_filters(std::span<const CanFilter> filters) = 0;
  virtual TransportStats stats() const = 0;
  virtual std::string name() const = 0;  // "socketcan:vcan0", "inprocess:bus0/rig"
};

// Error-frame classification shared by the backends (linux/can/error.h layout:
// id carries CAN_ERR_* class bits, data[1] the controller state).
struct ErrorFrameInfo {
  bool fatal = false;   // bus-off or error passive: the link cannot be trusted
  std::string text;     // "bus-off", "controller error passive (rx)", ...
};
ErrorFrameInfo classify_error_frame(const CanFrame& f);

bool filter_accepts(std::span<const CanFilter> filters, const CanFrame& f);

}  // namespace rig::link
