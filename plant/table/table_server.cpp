#include "plant/table/table_server.hpp"

#include <modbus/modbus.h>
#include <netinet/in.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <set>
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

constexpr int kMapSize = 256;  // libmodbus's reply buffer; the emulator decides what is valid
constexpr double kSelectS = 0.005;

uint16_t be16(const uint8_t* p) { return static_cast<uint16_t>((p[0] << 8) | p[1]); }

// Answers one request from the emulator's register map with proper exception
// codes; requests go unanswered while the emulator plays "no answer".
void serve_request(modbus_t* ctx, modbus_mapping_t* map, TableEmulator& emu, const uint8_t* q, int len) {
  if (!emu.answering()) return;
  const int off = modbus_get_header_length(ctx);
  const uint8_t fc = q[off];
  const uint16_t addr = be16(q + off + 1);
  uint8_t code = m::exc::kNone;
  switch (fc) {
    case MODBUS_FC_READ_HOLDING_REGISTERS:
    case MODBUS_FC_READ_INPUT_REGISTERS: {
      const uint16_t n = be16(q + off + 3);
      uint16_t buf[125];
      code = n > 125 ? m::exc::kIllegalValue : emu.read_registers(addr, n, buf);
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
    : emu_(emu), ep_(m::parse_endpoint(spec)), unit_(unit), steps_model_(steps_model) {
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
    if (impl->listen_fd < 0) throw HardwareError("table server: cannot listen on " + ep_.str() + ": " + modbus_strerror(errno));
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
  while (!stop_) {
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
    if (steps_model_) {
      const auto now = clk::now();
      emu_.step(std::chrono::duration<double>(now - last).count());
      last = now;
    }
    if (n <= 0) continue;
    if (s.listen_fd >= 0 && FD_ISSET(s.listen_fd, &rd)) {
      const int fd = ::accept4(s.listen_fd, nullptr, nullptr, SOCK_CLOEXEC);
      if (fd >= 0) s.clients.insert(fd);
    }
    if (s.port_fd >= 0 && FD_ISSET(s.port_fd, &rd)) {
      const int rc = modbus_receive(s.ctx, query.data());
      if (rc > 0) {
        serve_request(s.ctx, s.map, emu_, query.data(), rc);
        ++served_;
      } else if (rc < 0) {
        modbus_flush(s.ctx);  // bad CRC / partial frame: resynchronise on the next frame
        if (errno == EIO || errno == EBADF) std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
    }
    std::vector<int> closed;
    for (int fd : s.clients) {
      if (!FD_ISSET(fd, &rd)) continue;
      modbus_set_socket(s.ctx, fd);
      const int rc = modbus_receive(s.ctx, query.data());
      if (rc > 0) {
        serve_request(s.ctx, s.map, emu_, query.data(), rc);
        ++served_;
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
