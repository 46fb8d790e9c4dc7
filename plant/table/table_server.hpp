// The emulated table as a real Modbus slave: a libmodbus server (TCP on any
// address, or RTU on a serial device such as one end of a socat pty pair) in
// its own thread, stepping the emulator by wall time. For `rig plant serve`
// and for tests that drive the real client over a real wire.
#pragma once
#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "plant/table/table_emulator.hpp"
#include "rig/modbus/transport.hpp"

namespace rig::plant {

class TableServer {
 public:
  // `spec`: "tcp:HOST:PORT" (PORT 0 = pick a free port; see endpoint()) or
  // "rtu:DEVICE[,BAUD[,P,D,S]]". `unit`: the RTU slave id (TCP answers any).
  // `steps_model`: the server advances `emu` by wall time (false when some
  // other loop owns the emulator's time).
  TableServer(TableEmulator& emu, const std::string& spec, int unit = 1, bool steps_model = true);
  // Any register device (the emulated CiA 402 drive); `step` advances its
  // model by wall time (empty when some other loop owns its time).
  TableServer(rig::modbus::RegisterDevice& dev, std::function<void(double)> step, const std::string& spec,
              int unit = 1);
  ~TableServer();
  TableServer(const TableServer&) = delete;
  TableServer& operator=(const TableServer&) = delete;

  // Binds / opens the port (throws ConfigError for a bad spec, HardwareError
  // when the port cannot be opened), then serves in a background thread.
  void start();
  // Stops serving and closes every connection; returns within ~20 ms. Idempotent.
  void stop();
  // The canonical endpoint, with the bound port: "tcp:127.0.0.1:40123".
  std::string endpoint() const;
  // Requests answered for this unit, each counted before its reply is sent.
  uint64_t requests_served() const { return served_.load(); }
  // What the serving thread has to say (an RTU port that failed, reopened); set before start().
  void on_notice(std::function<void(const std::string&)> fn) { notice_ = std::move(fn); }

 private:
  struct Impl;
  void run();

  rig::modbus::RegisterDevice& emu_;
  std::function<void(double)> step_;
  std::function<void(const std::string&)> notice_;
  rig::modbus::Endpoint ep_;
  int unit_;
  std::unique_ptr<Impl> impl_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> served_{0};
};

}  // namespace rig::plant
