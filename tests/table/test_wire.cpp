// Client and emulator on a real wire: libmodbus at both ends, over loopback
// TCP and over an RTU pseudo-terminal pair made by socat; a server process
// killed mid-move; answer timeouts; exception replies.
#include <mutex>
#include <gtest/gtest.h>

#include <modbus/modbus.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <thread>

#include "helpers.hpp"
#include "plant/table/table_server.hpp"
#include "rig/core/clock.hpp"
#include "rig/modbus/table_client.hpp"

namespace rig::table_test {
namespace {

namespace m = rig::modbus;

// The response timeout is 1 s, not a tight 0.2 s: on a loaded machine (load 15-20 on two cores)
// the server thread, or socat relaying the RTU pty pair, can be off the CPU for a few hundred
// ms, and a spurious timeout then fails a test about something else. Tests of the timeout itself
// use a drive that never answers, so the outcome does not depend on the machine's speed.
constexpr double kTimeoutS = 1.0;
toml::table client_cfg(const std::string& key, const std::string& ep, const std::string& extra = "") {
  return cfg::parse_string(key + " = \"" + ep + "\"\nsettle_s = 0.1\nresponse_timeout_s = " + std::to_string(kTimeoutS) +
                               "\nretries = 1\n" + extra,
                           "hardware.toml");
}

// The angle in "... (last seen at X°)" of a link failure; NaN when the message has none.
double last_seen_deg(const std::string& err) {
  const std::string key = "(last seen at ";
  const std::size_t at = err.find(key);
  return at == std::string::npos ? std::nan("") : std::strtod(err.c_str() + at + key.size(), nullptr);
}

double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

template <class F>
std::string hardware_error(F f) {
  try {
    f();
  } catch (const HardwareError& e) {
    return e.what();
  }
  return "(no HardwareError)";
}

TEST(TableWire, HomeAndMoveOverLoopbackTcp) {
  auto emu = emulator(kFastTable);
  plant::TableServer server(*emu, "tcp:127.0.0.1:0");
  server.start();
  ASSERT_NE(server.endpoint(), "tcp:127.0.0.1:0");
  RealClock clock;
  auto table = m::connect_table(client_cfg("modbus", server.endpoint()), clock);
  EXPECT_EQ(table->describe(), "modbus " + server.endpoint() + " unit 1");
  // The travel as the drive's LIMIT_NEG / LIMIT_POS registers hold it (the emulator's defaults).
  const auto travel = table->travel_deg({});
  ASSERT_TRUE(travel);
  EXPECT_DOUBLE_EQ(travel->first, -190.0);
  EXPECT_DOUBLE_EQ(travel->second, 370.0);
  table->home({});
  table->move_to(180.0, {});
  const TableStatus s = table->status();
  EXPECT_TRUE(s.in_position);
  EXPECT_NEAR(s.actual_deg, 180.0, 0.01);
  EXPECT_NEAR(emu->actual_angle_deg(), 180.0, 0.005);
  table->move_to(-90.0, {});
  EXPECT_NEAR(table->status().actual_deg, -90.0, 0.01);
  EXPECT_GT(server.requests_served(), 10u);
}

TEST(TableWire, HomeAndMoveOverRtuPtyPair) {
  PtyPair pty;
  auto emu = emulator(kFastTable);
  plant::TableServer server(*emu, "rtu:" + pty.a() + ",115200,N,8,1", 5);
  server.start();
  RealClock clock;
  auto table = m::connect_table(client_cfg("rtu", pty.b() + ",115200,N,8,1", "unit = 5\n"), clock);
  table->home({});
  table->move_to(90.0, {});
  EXPECT_NEAR(table->status().actual_deg, 90.0, 0.01);
  // Another unit id on the same line gets no answer: a timeout, not a wrong reply.
  m::LinkOptions other;
  other.unit = 6;
  other.response_timeout_s = 0.1;
  other.retries = 0;
  auto t6 = m::make_libmodbus_transport(m::parse_rtu(pty.b() + ",115200,N,8,1"), other, clock);
  try {
    t6->read(0, 1, {});
    FAIL() << "unit 6 answered";
  } catch (const m::ModbusError& e) {
    EXPECT_TRUE(e.timeout) << e.what();
  }
}

// The RTU cable pulled while the server runs: the server says so once (it retried every 10 ms in
// silence, looking alive) and reopens the port when it comes back under its name.
TEST(TableWire, AnRtuPortThatWentAwayIsSaidAndReopened) {
  PtyPair pty;
  auto emu = emulator(kFastTable);
  plant::TableServer server(*emu, "rtu:" + pty.a() + ",115200,N,8,1", 5);
  std::mutex mu;
  std::vector<std::string> notices;
  server.on_notice([&](const std::string& t) {
    std::lock_guard lk(mu);
    notices.push_back(t);
  });
  server.start();
  const auto said = [&](const std::string& what) {
    for (int i = 0; i < 500; ++i) {
      {
        std::lock_guard lk(mu);
        for (const auto& n : notices)
          if (n.find(what) != std::string::npos) return n;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return std::string("(not said)");
  };
  pty.unplug();
  EXPECT_EQ(said("cannot be read"), "serial port " + pty.a() +
                                        ": cannot be read (end of file): its other end closed or the device went "
                                        "away; reopening it every second");
  pty.plug();
  EXPECT_EQ(said("open again"), "serial port " + pty.a() + ": open again, serving");
  RealClock clock;
  auto table = m::connect_table(client_cfg("rtu", pty.b() + ",115200,N,8,1", "unit = 5\n"), clock);
  table->home({});
  EXPECT_GT(server.requests_served(), 0u);
  std::lock_guard lk(mu);
  EXPECT_EQ(notices.size(), 2u) << "each said once";
}

TEST(TableWire, ExceptionRepliesAreNamed) {
  auto emu = emulator(kFastTable);
  plant::TableServer server(*emu, "tcp:127.0.0.1:0");
  server.start();
  RealClock clock;
  m::LinkOptions lo;
  auto t = m::make_libmodbus_transport(m::parse_endpoint(server.endpoint()), lo, clock);
  auto expect_exc = [&](auto f, uint8_t code, const std::string& text, const std::string& where) {
    try {
      f();
      ADD_FAILURE() << "no exception reply, expected " << text;
    } catch (const m::ModbusError& e) {
      EXPECT_EQ(e.exception_code, code) << e.what();
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what();
    }
  };
  expect_exc([&] { t->read(40, 2, {}); }, m::exc::kIllegalAddress, "read 2 registers at 40", server.endpoint());
  expect_exc([&] { t->read(40, 2, {}); }, m::exc::kIllegalAddress, "exception 0x02 illegal data address", server.endpoint());
  expect_exc([&] { t->write(m::reg::kStatus, {1}, {}); }, m::exc::kIllegalAddress, "illegal data address", server.endpoint());
  expect_exc([&] { t->write(m::reg::kTargetPos, {0x7FFF, 0xFFFF}, {}); }, m::exc::kIllegalValue, "illegal data value", server.endpoint());
  // Busy: a new target while homing.
  auto slow = emulator("start_angle_deg = 200.0\n");  // a long homing run
  plant::TableServer server2(*slow, "tcp:127.0.0.1:0");
  server2.start();
  auto t2 = m::make_libmodbus_transport(m::parse_endpoint(server2.endpoint()), lo, clock);
  t2->write(m::reg::kControl, {m::ctl::kServoOn}, {});
  t2->write(m::reg::kControl, {m::ctl::kServoOn | m::ctl::kHome}, {});
  expect_exc([&] { t2->write(m::reg::kTargetPos, {0, 10}, {}); }, m::exc::kBusy, "server device busy", server2.endpoint());
  // A function code the drive does not implement (read coils), straight from libmodbus.
  const m::Endpoint ep = m::parse_endpoint(server.endpoint());
  modbus_t* raw = modbus_new_tcp_pi(ep.host.c_str(), std::to_string(ep.port).c_str());
  ASSERT_EQ(modbus_connect(raw), 0);
  uint8_t bits[4];
  EXPECT_EQ(modbus_read_bits(raw, 0, 1, bits), -1);
  EXPECT_EQ(errno, EMBXILFUN);
  modbus_close(raw);
  modbus_free(raw);
}

TEST(TableWire, BusyRepliesAreRetriedWithBackoff) {
  auto emu = emulator(kFastTable);
  plant::TableServer server(*emu, "tcp:127.0.0.1:0");
  server.start();
  RealClock clock;
  m::LinkOptions lo;
  lo.retries = 5;  // backoff 0.05, 0.1, 0.2, 0.4, 0.8 s: outlasts a 0.2 s homing run
  auto t = m::make_libmodbus_transport(m::parse_endpoint(server.endpoint()), lo, clock);
  t->write(m::reg::kControl, {m::ctl::kServoOn}, {});
  t->write(m::reg::kControl, {m::ctl::kServoOn | m::ctl::kHome}, {});
  ASSERT_TRUE(emu->snapshot().homing);
  t->write(m::reg::kTargetPos, {0, 1000}, {});  // busy at first, accepted once homed
  EXPECT_TRUE(emu->snapshot().homed);
  EXPECT_EQ(m::join_i32(t->read(m::reg::kTargetPos, 2, {})[0], t->read(m::reg::kTargetPos, 2, {})[1]), 1000);
}

// A link on which nothing ever answered (a wrong unit id, baud rate or wiring) says what to
// check; "timeout" alone sent a technician looking for a dead drive (a review).
TEST(TableWire, ALinkThatNeverAnsweredSaysWhatToCheck) {
  auto emu = emulator(kFastTable);
  plant::TableServer server(*emu, "tcp:127.0.0.1:0");
  server.start();
  emu->inject(SimFault::kNoAnswer);
  RealClock clock;
  m::LinkOptions lo;
  lo.response_timeout_s = 0.05;
  lo.retries = 0;
  auto t = m::make_libmodbus_transport(m::parse_endpoint(server.endpoint()), lo, clock);
  try {
    t->read(0, 2, {});
    ADD_FAILURE() << "no error";
  } catch (const m::ModbusError& e) {
    EXPECT_NE(std::string(e.what()).find("no answer within 0.05 s (timeout); nothing has answered on this link yet: "
                                         "check the drive's unit id, whether the drive is running (one that hangs is silent too), or "
                                         "whether it answers later than 0.05 s (the "
                                         "response timeout: `rig table --timeout S`, [table] response_timeout_s"),
              std::string::npos)
        << e.what();
  }
}

// The emulated drive answers its own unit id over TCP (and 0 and 255, TCP's ids for a device
// reached directly; pymodbus at 255 checked by hand, the rig's transport sends 0..247); another gets
// exception 0x0B as from a gateway, with what to check. It answered any unit, so a hardware file
// with the wrong unit passed every check against the emulator (a review).
TEST(TableWire, ATcpRequestForAnotherUnitIsAnsweredAsAGatewayWould) {
  auto emu = emulator(kFastTable);
  plant::TableServer server(*emu, "tcp:127.0.0.1:0", 17);
  server.start();
  RealClock clock;
  for (const int unit : {17, 0, 3}) {
    m::LinkOptions lo;
    lo.unit = unit;
    auto t = m::make_libmodbus_transport(m::parse_endpoint(server.endpoint()), lo, clock);
    if (unit != 3) {
      EXPECT_NO_THROW(t->read(0, 2, {})) << unit;
      continue;
    }
    try {
      t->read(0, 2, {});
      ADD_FAILURE() << "no error";
    } catch (const m::ModbusError& e) {
      EXPECT_EQ(e.exception_code, 0x0B);
      EXPECT_NE(std::string(e.what()).find("exception 0x0B gateway target failed to respond (no device at this unit "
                                           "id? check the unit id: [table] unit, --unit)"),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(TableWire, AnswerTimeoutFailsBoundedWithAClearError) {
  auto emu = emulator(kFastTable);
  plant::TableServer server(*emu, "tcp:127.0.0.1:0");
  server.start();
  RealClock clock;
  auto table = m::connect_table(client_cfg("modbus", server.endpoint()), clock);
  table->home({});
  emu->inject(SimFault::kNoAnswer);
  const auto t0 = std::chrono::steady_clock::now();
  const std::string err = hardware_error([&] { table->move_to(45.0, {}); });
  const double elapsed = since(t0);
  EXPECT_NE(err.find("move to 45.0000°: link failure (last seen at "), std::string::npos) << err;
  // Where the table was last seen: home, within the client's tolerance (the homed position the
  // emulator settles at is 0 ± a few 1e-4°, depending on how its steps fell).
  EXPECT_NEAR(last_seen_deg(err), 0.0, 0.01) << err;
  EXPECT_NE(err.find("no answer within 1 s (timeout)"), std::string::npos) << err;
  EXPECT_EQ(err.find("nothing has answered"), std::string::npos) << "it answered before: " << err;
  // 2 attempts x 1 s + backoff, then a stop attempt of 2 x 1 s (about 4 s): at least the two
  // timed-out attempts were waited for, and the failure is bounded (generously: a loaded machine).
  EXPECT_GE(elapsed, 2 * kTimeoutS);
  EXPECT_LT(elapsed, 30.0);
  auto* client = dynamic_cast<m::TableClient*>(table.get());
  EXPECT_NE(client->last_stop_error().find("timeout"), std::string::npos) << client->last_stop_error();
  // The drive answers again: the client reconnects by itself.
  emu->clear_no_answer();
  table->move_to(45.0, {});
  EXPECT_NEAR(table->status().actual_deg, 45.0, 0.01);
}

TEST(TableWire, ReconnectsAfterTheServerComesBack) {
  auto emu = emulator(kFastTable);
  auto server = std::make_unique<plant::TableServer>(*emu, "tcp:127.0.0.1:0");
  server->start();
  const std::string ep = server->endpoint();
  RealClock clock;
  auto table = m::connect_table(client_cfg("modbus", ep), clock);
  table->home({});
  server.reset();  // the drive's Ethernet goes away...
  const std::string err = hardware_error([&] { table->status(); });
  EXPECT_NE(err.find("table status: read 25 registers at 0 on modbus " + ep), std::string::npos) << err;
  server = std::make_unique<plant::TableServer>(*emu, ep);  // ...and comes back on the same port
  server->start();
  table->move_to(33.0, {});
  EXPECT_NEAR(table->status().actual_deg, 33.0, 0.01);
}

// A drive that restarts mid-move (a power blip): it answers again on the same address, unhomed,
// servo off, with its power-on target. The client says so; it used to blame another master.
TEST(TableWire, ADriveRestartedMidMoveIsNamedAsSuch) {
  const char* const drive = "velocity_dps = 60.0\naccel_dps2 = 600.0\nstart_angle_deg = 1.0\nhome_velocity_dps = 100.0\n";
  auto emu = emulator(drive);
  auto after_restart = emulator(drive);
  auto server = std::make_unique<plant::TableServer>(*emu, "tcp:127.0.0.1:0");
  server->start();
  const std::string ep = server->endpoint();
  RealClock clock;
  auto table = m::connect_table(client_cfg("modbus", ep), clock);
  table->home({});
  std::thread restart([&] {
    for (int i = 0; i < 1000 && !(emu->snapshot().moving && emu->snapshot().position_deg > 30.0); ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    server.reset();  // the drive goes down...
    server = std::make_unique<plant::TableServer>(*after_restart, ep);  // ...and powers up again
    server->start();
  });
  const std::string err = hardware_error([&] { table->move_to(180.0, {}); });
  restart.join();
  EXPECT_NE(err.find("move to 180.0000°: the drive reports not homed and servo off mid-move (the drive restarted or "
                     "was power-cycled?)"),
            std::string::npos)
      << err;
  EXPECT_EQ(err.find("another Modbus master"), std::string::npos) << err;
}

TEST(TableWire, EmulatorKilledMidMove) {
  int out = -1;
  Child server({TABLE_TEST_SERVER, "tcp:127.0.0.1:0",
                "velocity_dps = 60.0\naccel_dps2 = 600.0\nstart_angle_deg = 1.0\nhome_velocity_dps = 100.0\n"},
               &out);
  const std::string line = read_line(out);
  close(out);
  ASSERT_EQ(line.rfind("listening tcp:", 0), 0u) << line;
  const std::string ep = line.substr(10);
  RealClock clock;
  auto table = m::connect_table(client_cfg("modbus", ep), clock);
  table->home({});
  // A second master watches the move and kills the server once it is under way.
  std::atomic<bool> killed{false};
  std::thread killer([&] {
    m::LinkOptions lo;
    auto watch = m::make_libmodbus_transport(m::parse_endpoint(ep), lo, clock);
    for (int i = 0; i < 1000; ++i) {
      const auto r = watch->read(0, m::reg::kBlockEnd, {});
      const int32_t pos = m::join_i32(r[m::reg::kActualPos], r[m::reg::kActualPos + 1]);
      if ((r[m::reg::kStatus] & m::sts::kMoving) && pos > 300000) break;  // past 30°
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    server.kill_now();
    killed = true;
  });
  const auto t0 = std::chrono::steady_clock::now();
  const std::string err = hardware_error([&] { table->move_to(180.0, {}); });
  killer.join();
  ASSERT_TRUE(killed);
  EXPECT_NE(err.find("move to 180.0000°: link failure (last seen at"), std::string::npos) << err;
  EXPECT_LT(since(t0), 5.0);  // the move itself would take 3.1 s; the failure is prompt
  auto* client = dynamic_cast<m::TableClient*>(table.get());
  EXPECT_NE(client->last_stop_error(), "");
  // stop() on the dead link stays bounded and quiet.
  const auto t1 = std::chrono::steady_clock::now();
  table->stop();
  table->quick_stop();
  EXPECT_LT(since(t1), 2.0);
  EXPECT_NE(client->last_stop_error().find("cannot connect"), std::string::npos) << client->last_stop_error();
}

TEST(TableWire, CancelFromAnotherThreadStopsTheTable) {
  auto emu = emulator("velocity_dps = 60.0\naccel_dps2 = 600.0\nstart_angle_deg = 1.0\nhome_velocity_dps = 100.0\n");
  plant::TableServer server(*emu, "tcp:127.0.0.1:0");
  server.start();
  RealClock clock;
  auto table = m::connect_table(client_cfg("modbus", server.endpoint()), clock);
  table->home({});
  CancelSource cs;
  std::thread executive([&] {
    while (emu->snapshot().position_deg < 30.0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    cs.request("e-stop line");
  });
  EXPECT_THROW(table->move_to(180.0, cs.token()), AbortedError);
  executive.join();
  for (int i = 0; i < 200 && emu->snapshot().moving; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_FALSE(emu->snapshot().moving);
  EXPECT_LT(emu->snapshot().position_deg, 90.0);
}

TEST(TableWire, ConnectToNothingIsAHardwareError) {
  RealClock clock;
  const std::string err = hardware_error([&] {
    m::connect_table(client_cfg("modbus", "127.0.0.1:1"), clock);
  });
  EXPECT_NE(err.find("modbus tcp:127.0.0.1:1 unit 1: cannot connect"), std::string::npos) << err;
}

}  // namespace
}  // namespace rig::table_test
