#include "plant/table/table_server.hpp"

#include <modbus/modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <termios.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <set>
#include <thread>
#include <vector>

#include "rig/core/errors.hpp"

namespace rig::plant {

namespace m = rig::modbus;

struct TableServer::Impl {
  modbus_t* ctx = nullptr;
  modbus_mapping_t* map = nullptr;
  int listen_fd = -1;  // TCP
  int port_fd = -1;    // RTU
  std::set<int> clients;
  int bound_port = 0;
  ~Impl() {
    for (int fd : clients) ::close(fd);
    if (listen_fd >= 0) ::close(listen_fd);
    if (ctx) {
      if (port_fd >= 0) modbus_close(ctx);
      modbus_free(ctx);
    }
    if (map) modbus_mapping_free(map);
  }
};

namespace {

constexpr int kMapSize = 65536;  // libmodbus's reply buffer over the whole address space (maps may sit anywhere); the emulator decides what is valid
constexpr double kSelectS = 0.005;

uint16_t be16(const uint8_t* p) { return static_cast<uint16_t>((p[0] << 8) | p[1]); }

// CRC-16/MODBUS (Modbus over Serial Line V1.02, section 6.2.2).
uint16_t crc16(const uint8_t* p, int n) {
  uint16_t crc = 0xFFFF;
  for (int i = 0; i < n; ++i) {
    crc ^= p[i];
    for (int b = 0; b < 8; ++b) crc = (crc & 1) ? static_cast<uint16_t>((crc >> 1) ^ 0xA001) : static_cast<uint16_t>(crc >> 1);
  }
  return crc;
}

// Reads `n` bytes, each within `gap_ms` of the previous (a frame arrives whole
// on a wire; a longer silence ends it). False on silence or error; `failed` set
// when the port itself failed, to the read's errno or -1 for an end of file (the
// pty's other end closed, the USB adapter was pulled), not on a silence.
bool read_exact(int fd, uint8_t* p, int n, int gap_ms, int& failed) {
  while (n > 0) {
    pollfd pf{fd, POLLIN, 0};
    if (poll(&pf, 1, gap_ms) <= 0) return false;
    const ssize_t r = ::read(fd, p, static_cast<size_t>(n));
    if (r <= 0) {
      if (r == 0 || (errno != EAGAIN && errno != EINTR)) failed = r == 0 ? -1 : errno;
      return false;
    }
    p += r;
    n -= static_cast<int>(r);
  }
  return true;
}

// One RTU request frame, its length from the function code, CRC checked.
// libmodbus's own modbus_receive() takes a request for another unit as the
// start of an exchange and then swallows the next frame as that unit's reply
// (issue 16 item 7): on a line where no other unit answers, our next request
// was lost. Framing here keeps every frame independent: a frame for another
// unit is skipped whole and the next one is read afresh.
// Returns the frame length, 0 for a frame to ignore, -1 on a framing error, -2
// when the port failed (`failed` as read_exact sets it).
int read_rtu_request(int fd, uint8_t* q, int cap, int& failed) {
  constexpr int kGapMs = 50;  // generous for ptys and USB adapters; 3.5 characters on a real line
  failed = 0;
  const auto got = [&](uint8_t* p, int n) { return read_exact(fd, p, n, kGapMs, failed); };
  if (!got(q, 2)) return failed ? -2 : -1;
  int len = 0;
  switch (q[1]) {
    case MODBUS_FC_READ_HOLDING_REGISTERS:
    case MODBUS_FC_READ_INPUT_REGISTERS:
    case MODBUS_FC_WRITE_SINGLE_REGISTER: len = 8; break;
    case MODBUS_FC_WRITE_MULTIPLE_REGISTERS:
      if (!got(q + 2, 5)) return failed ? -2 : -1;
      len = 9 + q[6];
      if (len > cap) return -1;
      if (!got(q + 7, len - 7)) return failed ? -2 : -1;
      break;
    default: return -1;  // a function this server does not serve (or noise): resynchronise
  }
  if (len == 8 && !got(q + 2, 6)) return failed ? -2 : -1;
  const uint16_t crc = crc16(q, len - 2);
  if (q[len - 2] != (crc & 0xFF) || q[len - 1] != (crc >> 8)) return -1;
  return len;
}

// Answers one request from the emulator's register map with proper exception
// codes; requests go unanswered while the emulator plays "no answer".
void serve_request(modbus_t* ctx, modbus_mapping_t* map, m::RegisterDevice& emu, const uint8_t* q, int len) {
  if (!emu.answering()) return;
  if (const double d = emu.answer_delay_s(); d > 0)  // injected slow answers
    std::this_thread::sleep_for(std::chrono::duration<double>(d));
  const int off = modbus_get_header_length(ctx);
  const uint8_t fc = q[off];
  const uint16_t addr = be16(q + off + 1);
  uint8_t code = m::exc::kNone;
  switch (fc) {
    case MODBUS_FC_READ_HOLDING_REGISTERS:
    case MODBUS_FC_READ_INPUT_REGISTERS: {
      const uint16_t n = be16(q + off + 3);
      uint16_t buf[125];
      if (n > 125) {
        code = m::exc::kIllegalValue;
      } else {
        code = fc == MODBUS_FC_READ_HOLDING_REGISTERS ? emu.read_registers(addr, n, buf)
                                                      : emu.read_input_registers(addr, n, buf);
      }
      if (code == m::exc::kNone) {
        uint16_t* tab = fc == MODBUS_FC_READ_HOLDING_REGISTERS ? map->tab_registers : map->tab_input_registers;
        std::memcpy(tab + addr, buf, n * sizeof(uint16_t));
      }
      break;
    }
    case MODBUS_FC_WRITE_SINGLE_REGISTER: {
      const uint16_t v = be16(q + off + 3);
      code = emu.write_registers(addr, &v, 1);
      break;
    }
    case MODBUS_FC_WRITE_MULTIPLE_REGISTERS: {
      const uint16_t n = be16(q + off + 3);
      const int bytes = q[off + 5];
      if (n < 1 || n > 123 || bytes != 2 * n || off + 6 + bytes > len) {
        code = m::exc::kIllegalValue;
        break;
      }
      std::vector<uint16_t> v(n);
      for (uint16_t i = 0; i < n; ++i) v[i] = be16(q + off + 6 + 2 * i);
      code = emu.write_registers(addr, v.data(), n);
      break;
    }
    default:
      code = m::exc::kIllegalFunction;
  }
  if (code != m::exc::kNone) {
    modbus_reply_exception(ctx, q, code);
  } else {
    modbus_reply(ctx, q, len, map);
  }
}

}  // namespace

TableServer::TableServer(TableEmulator& emu, const std::string& spec, int unit, bool steps_model)
    : TableServer(emu, steps_model ? std::function<void(double)>([&emu](double dt) { emu.step(dt); }) : nullptr, spec,
                  unit) {}

TableServer::TableServer(m::RegisterDevice& dev, std::function<void(double)> step, const std::string& spec, int unit)
    : emu_(dev), step_(std::move(step)), ep_(m::parse_endpoint(spec)), unit_(unit) {
  if (unit < 1 || unit > 247) throw ConfigError("table server: unit " + std::to_string(unit) + " out of range 1..247");
}

TableServer::~TableServer() { stop(); }

void TableServer::start() {
  if (thread_.joinable()) return;
  auto impl = std::make_unique<Impl>();
  impl->map = modbus_mapping_new_start_address(0, 0, 0, 0, 0, kMapSize, 0, kMapSize);
  if (ep_.kind == m::Endpoint::Kind::kTcp) {
    const std::string port = std::to_string(ep_.port);
    impl->ctx = modbus_new_tcp_pi(ep_.host.c_str(), port.c_str());
    if (!impl->ctx) throw HardwareError("table server " + ep_.str() + ": " + modbus_strerror(errno));
    impl->listen_fd = modbus_tcp_pi_listen(impl->ctx, 8);
    if (impl->listen_fd < 0) {
      const int e = errno;
      // libmodbus reports a host name it cannot resolve as ECONNREFUSED: `--modbus nohost:502`
      // said "Connection refused" (a review). Said as the table client says it.
      std::string why = e == ECONNREFUSED ? m::host_resolution_problem(ep_.host) : "";
      if (why.empty()) why = modbus_strerror(e);
      throw HardwareError("table server: cannot listen on " + ep_.str() + ": " + why);
    }
    sockaddr_storage sa{};
    socklen_t sl = sizeof sa;
    if (getsockname(impl->listen_fd, reinterpret_cast<sockaddr*>(&sa), &sl) == 0) {
      if (sa.ss_family == AF_INET) impl->bound_port = ntohs(reinterpret_cast<sockaddr_in*>(&sa)->sin_port);
      if (sa.ss_family == AF_INET6) impl->bound_port = ntohs(reinterpret_cast<sockaddr_in6*>(&sa)->sin6_port);
    }
    ep_.port = impl->bound_port;
  } else {
    impl->ctx = modbus_new_rtu(ep_.device.c_str(), ep_.baud, ep_.parity, ep_.data_bits, ep_.stop_bits);
    if (!impl->ctx) throw HardwareError("table server " + ep_.str() + ": " + modbus_strerror(errno));
    modbus_set_slave(impl->ctx, unit_);
    if (modbus_connect(impl->ctx) != 0)
      throw HardwareError("table server: cannot open " + ep_.device + ": " + modbus_strerror(errno));
    impl->port_fd = modbus_get_socket(impl->ctx);
  }
  impl_ = std::move(impl);
  stop_ = false;
  thread_ = std::thread([this] { run(); });
}

void TableServer::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  impl_.reset();
}

std::string TableServer::endpoint() const { return ep_.str(); }

void TableServer::run() {
  Impl& s = *impl_;
  std::vector<uint8_t> query(MODBUS_TCP_MAX_ADU_LENGTH > MODBUS_RTU_MAX_ADU_LENGTH ? MODBUS_TCP_MAX_ADU_LENGTH
                                                                                    : MODBUS_RTU_MAX_ADU_LENGTH);
  using clk = std::chrono::steady_clock;
  auto last = clk::now();
  auto reopen_at = clk::time_point{};
  // Said once per outage: a device that opens and fails again at once (EOF on every open) would
  // repeat both lines every second; they are said again only after a request was served.
  bool said_down = false, said_open = false;
  const auto notice = [&](const std::string& text) {
    if (notice_) notice_("serial port " + ep_.device + ": " + text);
  };
  while (!stop_) {
    // A serial port that failed is reopened every second: a USB adapter plugged back in, a socat
    // pty pair started again under the same link names (the old descriptor never reads again).
    if (s.ctx && s.listen_fd < 0 && s.port_fd < 0 && clk::now() >= reopen_at) {
      if (modbus_connect(s.ctx) == 0) {
        s.port_fd = modbus_get_socket(s.ctx);
        if (!said_open) notice("open again, serving");
        said_open = true;
      } else {
        reopen_at = clk::now() + std::chrono::seconds(1);
      }
    }
    fd_set rd;
    FD_ZERO(&rd);
    int maxfd = -1;
    auto add = [&](int fd) {
      FD_SET(fd, &rd);
      maxfd = std::max(maxfd, fd);
    };
    if (s.listen_fd >= 0) add(s.listen_fd);
    if (s.port_fd >= 0) add(s.port_fd);
    for (int fd : s.clients) add(fd);
    timeval tv{0, static_cast<suseconds_t>(kSelectS * 1e6)};
    const int n = select(maxfd + 1, &rd, nullptr, nullptr, &tv);
    if (step_) {
      const auto now = clk::now();
      step_(std::chrono::duration<double>(now - last).count());
      last = now;
    }
    if (n <= 0) continue;
    if (s.listen_fd >= 0 && FD_ISSET(s.listen_fd, &rd)) {
      const int fd = ::accept4(s.listen_fd, nullptr, nullptr, SOCK_CLOEXEC);
      if (fd >= 0) s.clients.insert(fd);
    }
    if (s.port_fd >= 0 && FD_ISSET(s.port_fd, &rd)) {
      int failed = 0;
      const int rc = read_rtu_request(s.port_fd, query.data(), static_cast<int>(query.size()), failed);
      if (rc > 0 && (query[0] == unit_ || query[0] == MODBUS_BROADCAST_ADDRESS)) {
        ++served_;  // before the reply, as below
        serve_request(s.ctx, s.map, emu_, query.data(), rc);
        said_down = said_open = false;
      } else if (rc == -2) {
        // Said once, not retried every 10 ms in silence (a review: EIO forever after socat
        // ended, the server looking alive).
        const std::string why = failed > 0 ? std::strerror(failed) : "end of file";
        modbus_close(s.ctx);
        s.port_fd = -1;
        reopen_at = clk::now() + std::chrono::seconds(1);
        if (!said_down)
          notice("cannot be read (" + why + "): its other end closed or the device went away; reopening it every second");
        said_down = true;
      } else if (rc < 0) {
        tcflush(s.port_fd, TCIFLUSH);  // bad CRC / partial frame: resynchronise on the next frame
      }
    }
    std::vector<int> closed;
    for (int fd : s.clients) {
      if (!FD_ISSET(fd, &rd)) continue;
      modbus_set_socket(s.ctx, fd);
      const int rc = modbus_receive(s.ctx, query.data());
      // A request for another unit id is answered as a gateway answers for a unit it has no
      // device at (exception 0x0B): it answered any unit over TCP, so a hardware file with the
      // wrong unit passed every check against the emulator and failed on the drive (a review).
      // 255 is Modbus TCP's "no unit" id and 0 its other choice for a device reached directly
      // (Modbus Messaging on TCP/IP, 4.4.1.2): both answered as before.
      if (rc > 0 && query[6] != unit_ && query[6] != 0xFF && query[6] != 0) {
        modbus_reply_exception(s.ctx, query.data(), 0x0B);
      } else if (rc > 0) {
        // Counted before the reply goes out: a client holding its answer finds its request
        // counted (counted after, a stop's two requests read as three now and then: the last
        // request of the command before it was counted after that command had exited).
        ++served_;
        serve_request(s.ctx, s.map, emu_, query.data(), rc);
      } else if (rc < 0) {
        closed.push_back(fd);
      }
    }
    for (int fd : closed) {
      ::close(fd);
      s.clients.erase(fd);
    }
  }
  if (s.ctx) modbus_set_socket(s.ctx, s.port_fd);
}

}  // namespace rig::plant
