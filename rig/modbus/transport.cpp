#include "rig/modbus/transport.hpp"

#include <arpa/inet.h>
#include <netdb.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <chrono>

#include <cctype>
#include <cerrno>
#include <charconv>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <sstream>

namespace rig::modbus {

// ---------------------------------------------------------------- endpoints

namespace {

// The address's numbers read like every other number the rig takes (README, "Numbers"): decimal
// digits, no sign, no leading zero, so "015610" or "+502" is a typo named here, not port 15610.
int parse_int(const std::string& s, const std::string& what, const std::string& spec) {
  int v = 0;
  const bool digits = !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (!digits) throw ConfigError("'" + spec + "': " + what + " '" + s + "' is not a number");
  if (s.size() > 1 && s[0] == '0')
    throw ConfigError("'" + spec + "': " + what + " '" + s + "' is not a decimal whole number (no leading zero)");
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || p != s.data() + s.size())
    throw ConfigError("'" + spec + "': " + what + " '" + s + "' out of range");
  return v;
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    if (c == sep) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

}  // namespace

std::string Endpoint::str() const {
  std::ostringstream os;
  if (kind == Kind::kTcp) {
    const bool v6 = host.find(':') != std::string::npos;
    os << "tcp:" << (v6 ? "[" : "") << host << (v6 ? "]" : "") << ':' << port;
  } else {
    os << "rtu:" << device << ',' << baud << ',' << parity << ',' << data_bits << ',' << stop_bits;
  }
  return os.str();
}

namespace {
// A host getaddrinfo can take: a name or IPv4 address (letters, digits, '.', '-', '_'), or an
// IPv6 address in brackets. Anything else ("zz zz", "udp:host") is a typo to name now, not a
// connect failure to report later as a hardware fault.
bool plausible_host(const std::string& h) {
  if (h.empty()) return false;
  for (const char ch : h) {
    const auto c = static_cast<unsigned char>(ch);
    if (!std::isalnum(c) && ch != '.' && ch != '-' && ch != '_') return false;
  }
  return true;
}
// An IPv6 address as inet_pton reads it ("fe80:::1" or "add:10.0.0.5" is a typo to name now),
// optionally with a zone (fe80::1%eth0) as getaddrinfo takes it.
bool plausible_ipv6(const std::string& h) {
  const auto zone = h.find('%');
  in6_addr a{};
  if (::inet_pton(AF_INET6, h.substr(0, zone).c_str(), &a) != 1) return false;
  return zone == std::string::npos || plausible_host(h.substr(zone + 1));
}
}  // namespace

std::string host_resolution_problem(const std::string& host) {
  addrinfo hints{};
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* res = nullptr;
  const int rc = ::getaddrinfo(host.c_str(), nullptr, &hints, &res);
  if (res) ::freeaddrinfo(res);
  if (rc == 0) return "";
  return "cannot resolve host name '" + host + "': " + ::gai_strerror(rc);
}

Endpoint parse_tcp(const std::string& host_port) {
  const auto colon = host_port.rfind(':');
  if (colon == std::string::npos || colon == 0)
    throw ConfigError("Modbus TCP address '" + host_port + "' must be HOST:PORT");
  Endpoint ep;
  ep.kind = Endpoint::Kind::kTcp;
  ep.host = host_port.substr(0, colon);
  const bool bracketed = ep.host.size() > 2 && ep.host.front() == '[' && ep.host.back() == ']';
  if (bracketed) ep.host = ep.host.substr(1, ep.host.size() - 2);
  // An IPv6 address without brackets (fd00::10:502) splits at its last ':' as it always did.
  if (!plausible_host(ep.host) && !plausible_ipv6(ep.host))
    throw ConfigError("Modbus TCP address '" + host_port + "': '" + host_port.substr(0, colon) +
                      "' is not a host name or address (HOST:PORT, tcp:HOST:PORT, tcp:[IPv6]:PORT or "
                      "rtu:DEVICE[,BAUD...])");
  ep.port = parse_int(host_port.substr(colon + 1), "port", host_port);
  if (ep.port < 0 || ep.port > 65535) throw ConfigError("Modbus TCP address '" + host_port + "': port out of range");
  return ep;
}

Endpoint parse_rtu(const std::string& dev_spec) {
  const auto parts = split(dev_spec, ',');
  Endpoint ep;
  ep.kind = Endpoint::Kind::kRtu;
  ep.device = parts[0];
  if (ep.device.empty()) throw ConfigError("Modbus RTU port '" + dev_spec + "' names no device");
  if (parts.size() >= 2) ep.baud = parse_int(parts[1], "baud rate", dev_spec);
  if (parts.size() == 3 || parts.size() > 5)
    throw ConfigError("Modbus RTU port '" + dev_spec + "' must be DEVICE[,BAUD[,PARITY,DATABITS,STOPBITS]]");
  if (parts.size() == 5) {
    if (parts[2].size() != 1 || std::string("NEOneo").find(parts[2][0]) == std::string::npos)
      throw ConfigError("Modbus RTU port '" + dev_spec + "': parity must be N, E or O");
    ep.parity = static_cast<char>(std::toupper(static_cast<unsigned char>(parts[2][0])));
    ep.data_bits = parse_int(parts[3], "data bits", dev_spec);
    ep.stop_bits = parse_int(parts[4], "stop bits", dev_spec);
    // Modbus RTU frames are 8-bit bytes (Modbus over serial line, 2.5.1): 7 data bits is ASCII mode's.
    if (ep.data_bits != 8)
      throw ConfigError("Modbus RTU port '" + dev_spec + "': " + std::to_string(ep.data_bits) +
                        " data bits: Modbus RTU needs 8");
    if (ep.stop_bits < 1 || ep.stop_bits > 2)
      throw ConfigError("Modbus RTU port '" + dev_spec + "': stop bits 1..2");
  }
  if (ep.baud <= 0) throw ConfigError("Modbus RTU port '" + dev_spec + "': baud rate must be positive");
  // libmodbus maps the baud rate to a termios speed and runs any other value at 9600 without a
  // word (a review: 11520 for 115200 ran at 9600): the serial port's speeds, or refused here.
  static constexpr int kBauds[] = {110,    300,    600,     1200,    2400,    4800,    9600,    19200,
                                   38400,  57600,  115200,  230400,  460800,  500000,  576000,  921600,
                                   1000000, 1152000, 1500000, 2000000, 2500000, 3000000, 3500000, 4000000};
  if (std::find(std::begin(kBauds), std::end(kBauds), ep.baud) == std::end(kBauds))
    throw ConfigError("Modbus RTU port '" + dev_spec + "': baud rate " + std::to_string(ep.baud) +
                      " is not a serial port speed (110, 300, ... 9600, 19200, 38400, 57600, 115200, 230400, ... "
                      "4000000)");
  return ep;
}

Endpoint parse_endpoint(const std::string& spec) {
  if (spec.rfind("tcp:", 0) == 0) return parse_tcp(spec.substr(4));
  if (spec.rfind("rtu:", 0) == 0) return parse_rtu(spec.substr(4));
  if (!spec.empty() && spec[0] == '/') return parse_rtu(spec);
  return parse_tcp(spec);
}

// ---------------------------------------------------------------- libmodbus

namespace {

bool is_exception_errno(int e, uint8_t* code) {
  const int c = e - MODBUS_ENOBASE;
  if (e >= EMBXILFUN && e <= EMBXGTAR && c >= 1 && c <= 11) {
    *code = static_cast<uint8_t>(c);
    return true;
  }
  return false;
}

std::string hex16(unsigned v) {
  char b[8];
  std::snprintf(b, sizeof b, "0x%02X", v);
  return b;
}

class LibmodbusTransport final : public RegisterTransport {
 public:
  LibmodbusTransport(const Endpoint& ep, const LinkOptions& opt, Clock& clock)
      : ep_(ep), opt_(opt), clock_(clock) {
    if (opt.unit < 0 || opt.unit > 247) throw ConfigError("Modbus unit " + std::to_string(opt.unit) + " out of range 0..247");
    if (ep.kind == Endpoint::Kind::kTcp) {
      const std::string port = std::to_string(ep.port);
      ctx_ = modbus_new_tcp_pi(ep.host.c_str(), port.c_str());
    } else {
      ctx_ = modbus_new_rtu(ep.device.c_str(), ep.baud, ep.parity, ep.data_bits, ep.stop_bits);
    }
    if (!ctx_) throw ModbusError(describe() + ": cannot create context: " + modbus_strerror(errno), 0, false);
    modbus_set_slave(ctx_, opt.unit);
    const double t = std::max(0.01, opt.response_timeout_s);
    const auto sec = static_cast<uint32_t>(t);
    const auto usec = static_cast<uint32_t>(std::lround((t - sec) * 1e6));
    modbus_set_response_timeout(ctx_, sec, usec);
    modbus_set_error_recovery(ctx_, MODBUS_ERROR_RECOVERY_NONE);
    std::lock_guard lk(mu_);
    std::string err;
    for (int attempt = 0;; ++attempt) {
      if (connect_locked(err)) break;
      if (attempt >= opt_.retries) {
        modbus_free(ctx_);
        ctx_ = nullptr;
        throw ModbusError(describe() + ": cannot connect: " + err, 0, false);
      }
      clock_.sleep_for(opt_.backoff_s * std::pow(2.0, attempt), CancelToken{});
    }
  }
  ~LibmodbusTransport() override {
    if (ctx_) {
      modbus_close(ctx_);
      modbus_free(ctx_);
    }
  }
  LibmodbusTransport(const LibmodbusTransport&) = delete;
  LibmodbusTransport& operator=(const LibmodbusTransport&) = delete;

  std::vector<uint16_t> read(uint16_t addr, uint16_t n, const CancelToken& cancel, bool urgent) override {
    std::vector<uint16_t> out(n);
    call("read " + std::to_string(n) + " registers at " + std::to_string(addr), cancel, urgent, [&] {
      return tcp() ? strict_read(MODBUS_FC_READ_HOLDING_REGISTERS, addr, n, out.data())
                   : modbus_read_registers(ctx_, addr, n, out.data());
    });
    return out;
  }

  std::vector<uint16_t> read_input(uint16_t addr, uint16_t n, const CancelToken& cancel, bool urgent) override {
    std::vector<uint16_t> out(n);
    call("read " + std::to_string(n) + " input registers at " + std::to_string(addr), cancel, urgent,
         [&] {
           return tcp() ? strict_read(MODBUS_FC_READ_INPUT_REGISTERS, addr, n, out.data())
                        : modbus_read_input_registers(ctx_, addr, n, out.data());
         });
    return out;
  }

  void write(uint16_t addr, const std::vector<uint16_t>& values, const CancelToken& cancel, bool urgent) override {
    const std::string what = "write " + std::to_string(values.size()) + " registers at " + std::to_string(addr);
    if (tcp()) {
      call(what, cancel, urgent, [&] { return strict_write(addr, values); });
    } else if (values.size() == 1) {
      call(what, cancel, urgent, [&] { return modbus_write_register(ctx_, addr, values[0]); });
    } else {
      call(what, cancel, urgent,
           [&] { return modbus_write_registers(ctx_, addr, static_cast<int>(values.size()), values.data()); });
    }
  }

  std::string describe() const override { return "modbus " + ep_.str() + " unit " + std::to_string(opt_.unit); }

 private:
  bool tcp() const { return ep_.kind == Endpoint::Kind::kTcp; }

  // ---- Modbus TCP with every response field checked (issue 13 item 8).
  // libmodbus 3.1.6 lets a wrong protocol id through (it tests both bytes
  // with &&), never compares the unit id of a TCP reply and reads the PDU by
  // its function code, ignoring the MBAP length; so the rig frames TCP itself
  // on libmodbus's connected socket: transaction id, protocol id 0, MBAP
  // length, unit id, function echo, byte count and write echo must all match
  // (Modbus Messaging on TCP/IP V1.0b, section 3.1.3; Application Protocol
  // V1.1b3, sections 6.3, 6.4, 6.6, 6.12). A violation fails the request like a
  // broken link (the connection is dropped, the request retried).
  int violation(const std::string& what) {
    violation_ = what;
    errno = EMBBADDATA;
    return -1;
  }

  // Reads exactly n bytes before `deadline`; false (errno ETIMEDOUT) when it passes.
  bool recv_exact(int fd, uint8_t* p, size_t n, std::chrono::steady_clock::time_point deadline) {
    while (n > 0) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      pollfd pf{fd, POLLIN, 0};
      const int pr = left.count() > 0 ? ::poll(&pf, 1, static_cast<int>(left.count())) : 0;
      if (pr == 0) {
        errno = ETIMEDOUT;
        return false;
      }
      if (pr < 0) return false;
      const ssize_t r = ::recv(fd, p, n, 0);
      if (r == 0) {
        errno = ECONNRESET;
        return false;
      }
      if (r < 0) {
        if (errno == EINTR) continue;
        return false;
      }
      p += r;
      n -= static_cast<size_t>(r);
    }
    return true;
  }

  // One request PDU out, its response PDU back, MBAP checked. -1 with errno on failure.
  int exchange(const std::vector<uint8_t>& pdu, std::vector<uint8_t>& rsp) {
    violation_.clear();
    foreign_frame_ = false;
    const int fd = modbus_get_socket(ctx_);
    const uint16_t tid = ++tid_;
    const auto len = static_cast<uint16_t>(pdu.size() + 1);
    std::vector<uint8_t> adu = {static_cast<uint8_t>(tid >> 8), static_cast<uint8_t>(tid & 0xFF), 0, 0,
                                static_cast<uint8_t>(len >> 8), static_cast<uint8_t>(len & 0xFF),
                                static_cast<uint8_t>(opt_.unit)};
    adu.insert(adu.end(), pdu.begin(), pdu.end());
    for (size_t off = 0; off < adu.size();) {
      const ssize_t w = ::send(fd, adu.data() + off, adu.size() - off, MSG_NOSIGNAL);
      if (w < 0) {
        if (errno == EINTR) continue;
        return -1;
      }
      off += static_cast<size_t>(w);
    }
    const auto deadline = std::chrono::steady_clock::now() +
                          std::chrono::microseconds(std::lround(std::max(0.01, opt_.response_timeout_s) * 1e6));
    uint8_t h[7];
    if (!recv_exact(fd, h, 7, deadline)) return -1;
    const uint16_t r_tid = static_cast<uint16_t>((h[0] << 8) | h[1]);
    const uint16_t r_proto = static_cast<uint16_t>((h[2] << 8) | h[3]);
    const uint16_t r_len = static_cast<uint16_t>((h[4] << 8) | h[5]);
    // Modbus TCP's protocol id is 0 in every frame: another one is another protocol (an HTTP
    // server's "HTTP/1.0" reads as transaction id 0x4854, protocol id 0x5450). A wrong
    // transaction or unit id, or a reply cut short, is a Modbus device misbehaving or slow:
    // devices in the field answer with unit id 0 or 255, and a gateway may split a late reply.
    // The protocol id first: another protocol's bytes make a transaction id too, and "transaction
    // id 18516 in reply to 3" hid that an HTTP server answered (a technician's re-test).
    foreign_frame_ = r_proto != 0;
    if (r_proto != 0) return violation("protocol id " + std::to_string(r_proto) + " (Modbus is 0)");
    if (r_tid != tid) return violation("transaction id " + std::to_string(r_tid) + " in reply to " + std::to_string(tid));
    if (r_len < 3 || r_len > 254) return violation("MBAP length " + std::to_string(r_len) + " out of range 3..254");
    if (h[6] != opt_.unit)
      return violation("unit id " + std::to_string(h[6]) + " in reply to unit " + std::to_string(opt_.unit));
    rsp.resize(r_len - 1u);
    if (!recv_exact(fd, rsp.data(), rsp.size(), deadline)) {
      if (errno == ETIMEDOUT)
        return violation("MBAP length " + std::to_string(r_len) + " but fewer bytes followed within the timeout");
      return -1;
    }
    if (rsp[0] == (pdu[0] | 0x80)) {  // exception reply: function | 0x80, one code byte
      if (rsp.size() != 2) return violation("exception reply of " + std::to_string(rsp.size()) + " bytes (MBAP length)");
      errno = MODBUS_ENOBASE + rsp[1];
      return -1;
    }
    if (rsp[0] != pdu[0])
      return violation("function " + hex16(rsp[0]) + " in reply to function " + hex16(pdu[0]));
    return 0;
  }

  int strict_read(uint8_t fc, uint16_t addr, uint16_t n, uint16_t* out) {
    std::vector<uint8_t> rsp;
    if (exchange({fc, static_cast<uint8_t>(addr >> 8), static_cast<uint8_t>(addr & 0xFF), static_cast<uint8_t>(n >> 8),
                  static_cast<uint8_t>(n & 0xFF)},
                 rsp) < 0)
      return -1;
    if (rsp.size() < 2 || rsp[1] != 2 * n || rsp.size() != 2u + 2u * n)
      return violation("reply to a read of " + std::to_string(n) + " registers carries byte count " +
                       std::to_string(rsp.size() > 1 ? rsp[1] : 0) + " in a PDU of " + std::to_string(rsp.size()) +
                       " bytes (MBAP length " + std::to_string(rsp.size() + 1) + ")");
    for (uint16_t i = 0; i < n; ++i) out[i] = static_cast<uint16_t>((rsp[2 + 2 * i] << 8) | rsp[3 + 2 * i]);
    return n;
  }

  int strict_write(uint16_t addr, const std::vector<uint16_t>& v) {
    std::vector<uint8_t> pdu;
    const auto hi = [](uint16_t x) { return static_cast<uint8_t>(x >> 8); };
    const auto lo = [](uint16_t x) { return static_cast<uint8_t>(x & 0xFF); };
    if (v.size() == 1) {
      pdu = {MODBUS_FC_WRITE_SINGLE_REGISTER, hi(addr), lo(addr), hi(v[0]), lo(v[0])};
    } else {
      const auto n = static_cast<uint16_t>(v.size());
      pdu = {MODBUS_FC_WRITE_MULTIPLE_REGISTERS, hi(addr), lo(addr), hi(n), lo(n), static_cast<uint8_t>(2 * n)};
      for (uint16_t x : v) {
        pdu.push_back(hi(x));
        pdu.push_back(lo(x));
      }
    }
    std::vector<uint8_t> rsp;
    if (exchange(pdu, rsp) < 0) return -1;
    // Function 06 echoes the request; function 16 echoes address and quantity.
    if (rsp.size() != 5 || !std::equal(rsp.begin(), rsp.end(), pdu.begin()))
      return violation("reply does not echo the write (" + std::to_string(rsp.size()) + " bytes)");
    return static_cast<int>(v.size());
  }

  bool connect_locked(std::string& err) {
    if (connected_) return true;
    if (modbus_connect(ctx_) == 0) {
      connected_ = true;
      return true;
    }
    // libmodbus connects without blocking and waits one response timeout; when nothing answers
    // in that time it returns with errno still EINPROGRESS ("Operation now in progress"), which
    // tells a technician nothing. A refused port gives ECONNREFUSED as it should.
    const int e = errno;
    if (e == EINPROGRESS) {
      std::ostringstream os;
      os << "no answer within " << std::max(0.01, opt_.response_timeout_s)
         << " s (host unreachable, off, or a firewall drops the connection)";
      err = os.str();
    } else if (e == ECONNREFUSED && ep_.kind == Endpoint::Kind::kTcp && !resolves(ep_.host, err)) {
      // libmodbus reports a name it cannot resolve as ECONNREFUSED, and no connection was tried:
      // say which (a review: "nosuchhost.invalid" was "Connection refused").
    } else {
      err = modbus_strerror(e);
    }
    modbus_close(ctx_);
    return false;
  }

  // Whether `host` resolves; if not, why, into `why`.
  static bool resolves(const std::string& host, std::string& why) {
    why = host_resolution_problem(host);
    return why.empty();
  }

  // One request with the retry policy. Exception replies are final except
  // "busy"; link failures close the connection so the next attempt reconnects.
  template <class Op>
  void call(const std::string& what, const CancelToken& cancel, bool urgent, Op op) {
    const int attempts = urgent ? 2 : 1 + std::max(0, opt_.retries);
    std::string last;
    bool last_timeout = false, foreign = false;  // of the last attempt: its failure is the one said
    uint8_t last_exc = 0;
    for (int attempt = 0; attempt < attempts; ++attempt) {
      if (!urgent) cancel.throw_if_requested();
      if (attempt > 0 && !urgent) clock_.sleep_for(opt_.backoff_s * std::pow(2.0, attempt - 1), cancel);
      // A serial line has no transaction id, and reopening the port does not stop a reply that is
      // still coming: after a timeout (or a reply that did not fit) the next request, this call's
      // retry or the next call's, waits until one response timeout has passed, so that a late
      // reply has arrived and is flushed below instead of being read as its own. A stop does not
      // wait (it is urgent; the flush still drops what has arrived).
      if (!urgent)
        if (const double wait = quiet_after_s_.load() - clock_.now_s(); wait > 0) clock_.sleep_for(wait, cancel);
      std::lock_guard lk(mu_);
      foreign = false;  // set below only by this attempt's reply in another protocol
      std::string err;
      if (!connect_locked(err)) {
        last = "cannot connect: " + err;
        last_timeout = false;
        last_exc = 0;
        continue;
      }
      if (!tcp()) modbus_flush(ctx_);  // RTU: what arrived since the last request is no reply to this one
      if (op() >= 0) {
        answered_ = true;
        return;
      }
      const int e = errno;
      uint8_t code = 0;
      if (is_exception_errno(e, &code)) {
        answered_ = true;
        last = "exception " + hex16(code) + " " + exception_text(code);
        last_exc = code;
        last_timeout = false;
        if (code != exc::kBusy) break;
        continue;
      }
      last_exc = 0;
      last_timeout = e == ETIMEDOUT;
      if (!tcp() && (last_timeout || e == EMBBADDATA)) quiet_after_s_ = clock_.now_s() + opt_.response_timeout_s;
      if (e == EMBBADDATA && !violation_.empty()) {
        last = "protocol violation: " + violation_;
        foreign = foreign_frame_;
      } else {
        last = last_timeout ? "no answer within " + fmt_s(opt_.response_timeout_s) + " (timeout)" : modbus_strerror(e);
      }
      // TCP: drop the link, so a late reply cannot be taken for the next request's. RTU: keep the
      // port open through a timeout or a misfit reply (the quiet wait and the flush above deal
      // with the late reply; closing a pty relayed by socat would end the relay); reopen it after
      // any other failure (a USB adapter unplugged).
      if (tcp() || !(last_timeout || e == EMBBADDATA)) {
        modbus_close(ctx_);
        connected_ = false;
      }
    }
    // Silence from the first request on is most often a wrong unit id or line setting, not a
    // dead drive (a review: a wrong --unit said only "timeout"), or a drive slower to answer than
    // the timeout (a review: a drive answering in 0.5 s was sent to check its unit id only).
    if (last_timeout && !answered_)
      // Nor is it always that: a drive that hangs is silent from this command's first request too
      // (a bring-up review: a drive that had just answered `status` was sent to check its unit id).
      last += (tcp() ? "; nothing has answered on this link yet: check the drive's unit id"
                     : "; nothing has answered on this line yet: check the drive's unit id, baud rate, parity and wiring") +
              std::string(", whether the drive is running (one that hangs is silent too)") +
              ", or whether it answers later than " + fmt_s(opt_.response_timeout_s) +
              " (the response timeout: `rig table --timeout S`, [table] response_timeout_s, at most 10 s)";
    throw ModbusError(what + " on " + describe() + ": " + last, last_exc, last_timeout, foreign);
  }

  static std::string fmt_s(double s) {
    char b[32];
    std::snprintf(b, sizeof b, "%.3g s", s);
    return b;
  }

  Endpoint ep_;
  LinkOptions opt_;
  Clock& clock_;
  std::mutex mu_;
  modbus_t* ctx_ = nullptr;
  bool connected_ = false;
  std::atomic<double> quiet_after_s_{0.0};  // RTU: clock time before which a late reply may still come
  std::atomic<bool> answered_{false};       // a request of this link has been answered (an exception too)
  uint16_t tid_ = 0;
  std::string violation_;
  bool foreign_frame_ = false;  // the last reply's MBAP header was not Modbus TCP's (protocol id != 0)
};

// ---------------------------------------------------------------- in-process

class InProcessTransport final : public RegisterTransport {
 public:
  InProcessTransport(RegisterDevice& dev, Clock& clock, double timeout_s)
      : dev_(dev), clock_(clock), timeout_s_(timeout_s) {}

  std::vector<uint16_t> read(uint16_t addr, uint16_t n, const CancelToken& cancel, bool urgent) override {
    const std::string what = "read " + std::to_string(n) + " registers at " + std::to_string(addr);
    wait_answer(what, cancel, urgent);
    std::vector<uint16_t> out(n);
    check(what, dev_.read_registers(addr, n, out.data()));
    return out;
  }

  std::vector<uint16_t> read_input(uint16_t addr, uint16_t n, const CancelToken& cancel, bool urgent) override {
    const std::string what = "read " + std::to_string(n) + " input registers at " + std::to_string(addr);
    wait_answer(what, cancel, urgent);
    std::vector<uint16_t> out(n);
    check(what, dev_.read_input_registers(addr, n, out.data()));
    return out;
  }

  void write(uint16_t addr, const std::vector<uint16_t>& values, const CancelToken& cancel, bool urgent) override {
    const std::string what = "write " + std::to_string(values.size()) + " registers at " + std::to_string(addr);
    wait_answer(what, cancel, urgent);
    check(what, dev_.write_registers(addr, values.data(), static_cast<uint16_t>(values.size())));
  }

  std::string describe() const override { return "in-process emulated table"; }

 private:
  // A silent device costs the response timeout of (simulated) time, as on a wire.
  void wait_answer(const std::string& what, const CancelToken& cancel, bool urgent) {
    if (!urgent) cancel.throw_if_requested();
    if (dev_.answering()) return;
    clock_.sleep_for(timeout_s_, urgent ? CancelToken{} : cancel);
    char t[32];
    std::snprintf(t, sizeof t, "%.3g s", timeout_s_);
    throw ModbusError(what + " on " + describe() + ": no answer within " + t + " (timeout)", 0, true);
  }
  void check(const std::string& what, uint8_t code) {
    if (code == exc::kNone) return;
    throw ModbusError(what + " on " + describe() + ": exception " + hex16(code) + " " + exception_text(code), code,
                      false);
  }

  RegisterDevice& dev_;
  Clock& clock_;
  double timeout_s_;
};

}  // namespace

std::unique_ptr<RegisterTransport> make_libmodbus_transport(const Endpoint& ep, const LinkOptions& opt, Clock& clock) {
  return std::make_unique<LibmodbusTransport>(ep, opt, clock);
}

std::unique_ptr<RegisterTransport> make_inprocess_transport(RegisterDevice& dev, Clock& clock,
                                                            double response_timeout_s) {
  return std::make_unique<InProcessTransport>(dev, clock, response_timeout_s);
}

}  // namespace rig::modbus
