#include "firmware_link/socketcan.hpp"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <mutex>
#include <thread>
#include <vector>

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

#include <asio/io_context.hpp>
#include <asio/posix/stream_descriptor.hpp>
#include <asio/write.hpp>

#include "rig/core/errors.hpp"

namespace rig::link {

namespace {

std::string sys_error(const std::string& what, int err) { return what + ": " + std::strerror(err); }

can_frame to_kernel(const CanFrame& f) {
  can_frame k{};
  k.can_id = f.extended ? ((f.id & CAN_EFF_MASK) | CAN_EFF_FLAG) : (f.id & CAN_SFF_MASK);
  if (f.rtr) k.can_id |= CAN_RTR_FLAG;
  if (f.error) k.can_id = (f.id & CAN_ERR_MASK) | CAN_ERR_FLAG;
  k.len = f.len;
  std::memcpy(k.data, f.data.data(), 8);
  return k;
}

CanFrame from_kernel(const can_frame& k) {
  CanFrame f;
  f.error = (k.can_id & CAN_ERR_FLAG) != 0;
  f.extended = (k.can_id & CAN_EFF_FLAG) != 0;
  f.rtr = (k.can_id & CAN_RTR_FLAG) != 0;
  f.id = f.error ? (k.can_id & CAN_ERR_MASK) : f.extended ? (k.can_id & CAN_EFF_MASK) : (k.can_id & CAN_SFF_MASK);
  f.len = std::min<uint8_t>(k.len, 8);
  std::memcpy(f.data.data(), k.data, 8);
  return f;
}

}  // namespace

struct SocketCanTransport::Impl {
  asio::io_context io;
  asio::posix::stream_descriptor sd{io};
  std::mutex tx_mu;  // send() may be called from the safe-state path on another thread
  std::atomic<uint64_t> tx{0}, rx{0}, rx_dropped{0}, error_frames{0};
};

bool socketcan_available() {
  const int s = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (s < 0) return false;
  ::close(s);
  return true;
}

SocketCanTransport::SocketCanTransport(const std::string& iface, SocketCanOptions opts)
    : impl_(std::make_unique<Impl>()), iface_(iface), opts_(opts) {
  const int s = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (s < 0) {
    const int e = errno;
    throw HardwareError(sys_error("CAN interface '" + iface + "': socket(AF_CAN, SOCK_RAW)", e) +
                        (e == EAFNOSUPPORT ? " (this kernel has no SocketCAN; load the can and can-raw modules)" : ""));
  }
  impl_->sd.assign(s);  // owns the fd from here on
  const unsigned idx = ::if_nametoindex(iface.c_str());
  if (idx == 0) throw HardwareError(sys_error("CAN interface '" + iface + "' not found", errno));

  // Options before bind so no frame slips through unfiltered.
  const can_err_mask_t err_mask = CAN_ERR_MASK;  // every error class; classify_error_frame decides
  ::setsockopt(s, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask);
  const int own = opts_.receive_own ? 1 : 0;
  ::setsockopt(s, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &own, sizeof own);
  const int one = 1;
  ::setsockopt(s, SOL_SOCKET, SO_TIMESTAMP, &one, sizeof one);
  // CAN FD frames too (DBC layouts of several samples per frame); classic ones are unchanged.
  ::setsockopt(s, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &one, sizeof one);
  ::setsockopt(s, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one);
  // SO_RCVBUFFORCE ignores rmem_max (needs CAP_NET_ADMIN); else the capped SO_RCVBUF.
  if (::setsockopt(s, SOL_SOCKET, SO_RCVBUFFORCE, &opts_.rcvbuf_bytes, sizeof opts_.rcvbuf_bytes) != 0)
    ::setsockopt(s, SOL_SOCKET, SO_RCVBUF, &opts_.rcvbuf_bytes, sizeof opts_.rcvbuf_bytes);

  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(idx);
  if (::bind(s, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0)
    throw HardwareError(sys_error("CAN interface '" + iface + "': bind", errno));
  impl_->sd.non_blocking(true);
}

SocketCanTransport::~SocketCanTransport() = default;

void SocketCanTransport::send(const CanFrame& f) {
  if (f.len > 8) throw HardwareError(name() + ": frame " + to_candump(f) + " longer than 8 bytes");
  const can_frame k = to_kernel(f);
  write_kernel(&k, sizeof k, to_candump(f));
}

void SocketCanTransport::send_fd(const CanFdFrame& f) {
  if (f.len > 64 || canfd_round_up(f.len) != f.len)
    throw HardwareError(name() + ": CAN FD frame of " + std::to_string(f.len) + " bytes");
  canfd_frame k{};
  k.can_id = f.extended ? ((f.id & CAN_EFF_MASK) | CAN_EFF_FLAG) : (f.id & CAN_SFF_MASK);
  k.len = f.len;
  k.flags = f.brs ? CANFD_BRS : 0;
  std::memcpy(k.data, f.data.data(), f.len);
  char what[48];
  std::snprintf(what, sizeof what, "CAN FD frame 0x%X (%d bytes)", f.id, f.len);
  write_kernel(&k, sizeof k, what);
}

void SocketCanTransport::write_kernel(const void* k, std::size_t n, const std::string& what) {
  std::lock_guard lk(impl_->tx_mu);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(opts_.send_timeout_s);
  for (;;) {
    asio::error_code ec;
    asio::write(impl_->sd, asio::buffer(k, n), ec);
    if (!ec) {
      ++impl_->tx;
      return;
    }
    // ENOBUFS: the interface's tx queue is full (the kernel never blocks CAN
    // writers on it); EAGAIN: the socket's send buffer is. Give them a moment.
    const bool full = ec.value() == ENOBUFS || ec == asio::error::would_block || ec == asio::error::try_again;
    if (full && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      continue;
    }
    // A CAN FD frame on a classic interface: the kernel refuses it with EINVAL.
    if (n == sizeof(canfd_frame) && ec.value() == EINVAL)
      throw HardwareError(name() + ": sending " + what + ": the interface is not in CAN FD mode (ip link set " + iface_ +
                          " mtu 72)");
    throw HardwareError(name() + ": sending " + what + ": " + ec.message());
  }
}

std::optional<RxFrame> SocketCanTransport::try_read() {
  canfd_frame k{};  // CAN_RAW_FD_FRAMES: classic frames arrive as CAN_MTU bytes, FD ones as CANFD_MTU
  iovec iov{&k, sizeof k};
  alignas(cmsghdr) char ctrl[CMSG_SPACE(sizeof(timeval)) + CMSG_SPACE(sizeof(uint32_t))];
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = ctrl;
  msg.msg_controllen = sizeof ctrl;
  const ssize_t n = ::recvmsg(impl_->sd.native_handle(), &msg, MSG_DONTWAIT);
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return std::nullopt;
    throw HardwareError(sys_error(name() + ": recvmsg", errno));
  }
  RxFrame rx;
  if (static_cast<std::size_t>(n) == CANFD_MTU) {
    CanFdFrame f;
    f.extended = (k.can_id & CAN_EFF_FLAG) != 0;
    f.id = f.extended ? (k.can_id & CAN_EFF_MASK) : (k.can_id & CAN_SFF_MASK);
    f.len = std::min<uint8_t>(k.len, 64);
    f.fd = true;
    f.brs = (k.flags & CANFD_BRS) != 0;
    std::memcpy(f.data.data(), k.data, f.len);
    rx.fd = f;
  } else if (static_cast<std::size_t>(n) == CAN_MTU) {
    can_frame c{};
    std::memcpy(&c, &k, sizeof c);
    rx.frame = from_kernel(c);
  } else {
    throw HardwareError(name() + ": short CAN frame read");
  }
  rx.t_s = now_s();  // replaced by the kernel's timestamp when the socket gives one
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level != SOL_SOCKET) continue;
    if (c->cmsg_type == SO_TIMESTAMP) {
      timeval tv;
      std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
      rx.t_s = static_cast<double>(tv.tv_sec) + static_cast<double>(tv.tv_usec) * 1e-6;
    } else if (c->cmsg_type == SO_RXQ_OVFL) {
      uint32_t dropped;  // cumulative frames dropped by this socket's full queue
      std::memcpy(&dropped, CMSG_DATA(c), sizeof dropped);
      impl_->rx_dropped = dropped;
    }
  }
  return rx;
}

double SocketCanTransport::now_s() const {
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

std::optional<RxFrame> SocketCanTransport::receive(double timeout_s, const CancelToken& cancel) {
  using clk = std::chrono::steady_clock;
  const clk::time_point deadline =
      clk::now() + std::chrono::duration_cast<clk::duration>(std::chrono::duration<double>(std::max(timeout_s, 0.0)));
  for (;;) {
    cancel.throw_if_requested();
    while (auto rx = try_read()) {
      if (rx->frame.error) {
        ++impl_->error_frames;
        const ErrorFrameInfo e = classify_error_frame(rx->frame);
        if (e.fatal) throw HardwareError(name() + ": CAN " + e.text);
        continue;
      }
      ++impl_->rx;
      return rx;
    }
    const clk::time_point now = clk::now();
    if (now >= deadline) return std::nullopt;
    // Wait for readability on the Asio descriptor, in slices so cancellation is prompt.
    const clk::duration slice = std::min<clk::duration>(deadline - now, std::chrono::milliseconds(20));
    bool ready = false;
    impl_->sd.async_wait(asio::posix::stream_descriptor::wait_read, [&ready](const asio::error_code& ec) {
      if (!ec) ready = true;
    });
    impl_->io.restart();
    impl_->io.run_for(slice);
    if (!ready) {  // timed out: cancel the wait and let its handler run before `ready` goes out of scope
      impl_->sd.cancel();
      impl_->io.restart();
      impl_->io.run();
    }
  }
}

void SocketCanTransport::set_filters(std::span<const CanFilter> filters) {
  std::vector<can_filter> k;
  for (const CanFilter& f : filters)  // data frames of the filter's kind: EFF and RTR are part of the match
    if (f.extended)
      k.push_back({(f.id & CAN_EFF_MASK) | CAN_EFF_FLAG, (f.mask & CAN_EFF_MASK) | CAN_EFF_FLAG | CAN_RTR_FLAG});
    else
      k.push_back({f.id & CAN_SFF_MASK, (f.mask & CAN_SFF_MASK) | CAN_EFF_FLAG | CAN_RTR_FLAG});
  if (k.empty()) k.push_back({0, 0});  // everything
  if (::setsockopt(impl_->sd.native_handle(), SOL_CAN_RAW, CAN_RAW_FILTER, k.data(),
                   static_cast<socklen_t>(k.size() * sizeof(can_filter))) != 0)
    throw HardwareError(sys_error(name() + ": setting receive filters", errno));
}

TransportStats SocketCanTransport::stats() const {
  TransportStats s;
  s.tx = impl_->tx;
  s.rx = impl_->rx;
  s.rx_dropped = impl_->rx_dropped;
  s.error_frames = impl_->error_frames;
  return s;
}

}  // namespace rig::link
