// SocketCAN transport on Asio: a CAN_RAW socket wrapped in an
// asio::posix::stream_descriptor (readiness waits with a timeout), recvmsg for
// the kernel's SO_TIMESTAMP and SO_RXQ_OVFL (drop counter) ancillary data,
// kernel-side receive filters, and error frames (bus-off, error passive) as
// HardwareError. Needs a kernel with AF_CAN (the build host has none: it is
// tested in the guest kernel, tests/kernel).
#pragma once
#include <memory>
#include <string>

#include "firmware_link/can_transport.hpp"

namespace rig::link {

struct SocketCanOptions {
  int rcvbuf_bytes = 8 << 20;  // a 1 kHz stream must survive scheduling hiccups (SO_RCVBUFFORCE as root)
  bool receive_own = false;    // CAN_RAW_RECV_OWN_MSGS
  double send_timeout_s = 0.1; // how long send() retries a full tx queue (ENOBUFS) before failing
};

class SocketCanTransport final : public CanTransport {
 public:
  // Throws HardwareError naming the interface when it cannot be opened.
  explicit SocketCanTransport(const std::string& iface, SocketCanOptions opts = {});
  ~SocketCanTransport() override;
  SocketCanTransport(const SocketCanTransport&) = delete;
  SocketCanTransport& operator=(const SocketCanTransport&) = delete;

  void send(const CanFrame& f) override;
  // Needs the interface in CAN FD mode (`ip link set IFACE mtu 72`), else HardwareError saying so.
  void send_fd(const CanFdFrame& f) override;
  std::optional<RxFrame> receive(double timeout_s, const CancelToken& cancel) override;
  double now_s() const override;  // CLOCK_REALTIME, the clock of the kernel's SO_TIMESTAMP
  void set_filters(std::span<const CanFilter> filters) override;
  TransportStats stats() const override;
  std::string name() const override { return "socketcan:" + iface_; }

 private:
  struct Impl;
  std::optional<RxFrame> try_read();  // one non-blocking recvmsg
  // Writes one kernel frame (can_frame or canfd_frame), retrying a full tx queue for send_timeout_s.
  void write_kernel(const void* k, std::size_t n, const std::string& what);
  std::unique_ptr<Impl> impl_;
  std::string iface_;
  SocketCanOptions opts_;
};

// True when this kernel can open a CAN_RAW socket (false on the build host).
bool socketcan_available();

}  // namespace rig::link
