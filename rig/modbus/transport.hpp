// Register transports: how the table client reaches a register map.
//  - libmodbus (TCP or RTU): response timeouts, retries with exponential
//    backoff (waited on the rig::Clock so cancellation is prompt), reconnect.
//  - in-process: direct calls into an emulated drive (no sockets), used by the
//    emulated plant under a SimClock.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rig/core/cancel.hpp"
#include "rig/core/clock.hpp"
#include "rig/core/errors.hpp"
#include "rig/modbus/registers.hpp"

namespace rig::modbus {

// Said where a call's reply was foreign: a stop is not sent into such a peer.
inline constexpr const char* kForeignPeer =
    "what answers there is no Modbus drive: check the host, port and unit id of the table";

// A failed register call. `exception_code` is the Modbus exception (0 when the
// failure was the link: timeout, connection, CRC). `foreign_reply`: the call's last attempt was
// answered in another protocol (on TCP, a frame whose protocol id is not Modbus's 0: an HTTP
// server, another service at the port). A Modbus frame with a wrong transaction or unit id, or a
// reply cut short by the timeout, is not foreign: a Modbus device sent it.
struct ModbusError : HardwareError {
  ModbusError(const std::string& what, uint8_t exception_reply, bool timed_out, bool foreign = false)
      : HardwareError(what), exception_code(exception_reply), timeout(timed_out), foreign_reply(foreign) {}
  uint8_t exception_code;
  bool timeout;
  bool foreign_reply;
};

// Where a drive is: "tcp:HOST:PORT" (also plain "HOST:PORT") or
// "rtu:DEVICE[,BAUD[,PARITY,DATABITS,STOPBITS]]" (defaults 19200,E,8,1: the
// Modbus serial line default).
struct Endpoint {
  enum class Kind { kTcp, kRtu } kind = Kind::kTcp;
  std::string host = "127.0.0.1";
  int port = 502;
  std::string device;
  int baud = 19200;
  char parity = 'E';
  int data_bits = 8;
  int stop_bits = 1;
  std::string str() const;  // canonical "tcp:127.0.0.1:1502" / "rtu:/dev/ttyUSB0,19200,E,8,1"
};
// Throws ConfigError naming the spec when it is malformed.
Endpoint parse_tcp(const std::string& host_port);    // "HOST:PORT"
Endpoint parse_rtu(const std::string& dev_spec);     // "DEV[,BAUD[,P,D,S]]"
Endpoint parse_endpoint(const std::string& spec);    // "tcp:..." | "rtu:..." | "HOST:PORT"

// Why `host` does not resolve ("cannot resolve host name 'HOST': ..."), or "" when it does.
// libmodbus reports a name it cannot resolve as ECONNREFUSED, client and server alike.
std::string host_resolution_problem(const std::string& host);

struct LinkOptions {
  int unit = 1;                    // Modbus unit (slave) id
  double response_timeout_s = 0.3; // per request
  int retries = 2;                 // extra attempts after a link failure (not after an exception reply)
  double backoff_s = 0.05;         // first retry delay, doubled per retry
};

class RegisterTransport {
 public:
  virtual ~RegisterTransport() = default;
  // `urgent` = the safe-state path: one attempt (plus one reconnect), no
  // backoff, so the call is bounded by about two response timeouts.
  virtual std::vector<uint16_t> read(uint16_t addr, uint16_t n, const CancelToken& cancel, bool urgent = false) = 0;
  // Function 04 (input registers); read() is function 03 (holding registers).
  virtual std::vector<uint16_t> read_input(uint16_t addr, uint16_t n, const CancelToken& cancel,
                                           bool urgent = false) = 0;
  virtual void write(uint16_t addr, const std::vector<uint16_t>& values, const CancelToken& cancel,
                     bool urgent = false) = 0;
  virtual std::string describe() const = 0;  // "modbus tcp:127.0.0.1:1502 unit 1"
};

// libmodbus client. Connects immediately (bounded by the response timeout per
// attempt); throws ModbusError when the drive cannot be reached.
std::unique_ptr<RegisterTransport> make_libmodbus_transport(const Endpoint& ep, const LinkOptions& opt, Clock& clock);

// Direct calls into `dev`. While the device does not answer, a call waits the
// response timeout on `clock` (simulated time) and fails like a real timeout.
std::unique_ptr<RegisterTransport> make_inprocess_transport(RegisterDevice& dev, Clock& clock,
                                                            double response_timeout_s = 0.3);

}  // namespace rig::modbus
