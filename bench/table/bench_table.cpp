// Figures for docs/table-registers.md:
//   build/bin/bench_table --benchmark_min_time=1
// - a status read (25 registers) over loopback TCP and over an RTU pty pair
//   (socat; a pty does not pace bytes at the baud rate, so this is the software cost),
// - a 180° move of the in-process emulated table under a SimClock (wall cost per move),
// - one simulated second of the drive model while moving.
#include <benchmark/benchmark.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "plant/table/table_server.hpp"
#include "rig/core/clock.hpp"
#include "rig/core/toml_util.hpp"
#include "plant/table/table_emulator.hpp"
#include "rig/modbus/table_client.hpp"

extern char** environ;

namespace {

namespace m = rig::modbus;

std::unique_ptr<rig::plant::TableEmulator> make_emu(const char* text) {
  const toml::table t = rig::cfg::parse_string(text, "bench.toml");
  return rig::plant::make_table_emulator(&t, 1);
}

void BM_TcpStatusRead(benchmark::State& state) {
  auto emu = make_emu("");
  rig::plant::TableServer server(*emu, "tcp:127.0.0.1:0");
  server.start();
  rig::RealClock clock;
  auto t = m::make_libmodbus_transport(m::parse_endpoint(server.endpoint()), m::LinkOptions{}, clock);
  for (auto _ : state) benchmark::DoNotOptimize(t->read(0, m::reg::kBlockEnd, {}));
}
BENCHMARK(BM_TcpStatusRead)->Unit(benchmark::kMicrosecond);

void BM_RtuStatusReadPty(benchmark::State& state) {
  char tmpl[] = "/tmp/rig-bench-pty-XXXXXX";
  const std::string dir = mkdtemp(tmpl), a = dir + "/a", b = dir + "/b";
  std::string la = "pty,raw,echo=0,link=" + a, lb = "pty,raw,echo=0,link=" + b;
  char* argv[] = {const_cast<char*>("/usr/bin/socat"), la.data(), lb.data(), nullptr};
  pid_t pid = -1;
  if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv, environ) != 0) {
    state.SkipWithError("socat not available");
    return;
  }
  for (int i = 0; i < 500 && !(std::filesystem::exists(a) && std::filesystem::exists(b)); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  {
    auto emu = make_emu("");
    rig::plant::TableServer server(*emu, "rtu:" + a + ",115200,N,8,1");
    server.start();
    rig::RealClock clock;
    auto t = m::make_libmodbus_transport(m::parse_rtu(b + ",115200,N,8,1"), m::LinkOptions{}, clock);
    for (auto _ : state) benchmark::DoNotOptimize(t->read(0, m::reg::kBlockEnd, {}));
  }
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_RtuStatusReadPty)->Unit(benchmark::kMicrosecond);

void BM_InProcessMove180(benchmark::State& state) {
  auto emu = make_emu("start_angle_deg = 0.0\n");
  rig::SimClock clock([&](double dt) { emu->step(dt); });
  auto table = m::make_inprocess_table(*emu, clock);
  table->home({});
  double target = 180.0, sim = 0;
  int moves = 0;
  for (auto _ : state) {
    const double t0 = clock.now_s();
    table->move_to(target, {});
    sim += clock.now_s() - t0;
    ++moves;
    target = 180.0 - target;
  }
  state.counters["sim_s_per_move"] = sim / moves;
}
BENCHMARK(BM_InProcessMove180)->Unit(benchmark::kMillisecond);

void BM_DriveModelOneSimSecond(benchmark::State& state) {
  auto emu = make_emu("start_angle_deg = 0.0\nhomed_at_start = true\nvelocity_dps = 1.0\n");
  uint16_t w[2];
  m::split_i32(3000000, w);
  emu->write_registers(m::reg::kTargetPos, w, 2);
  const uint16_t on = m::ctl::kServoOn, start = m::ctl::kServoOn | m::ctl::kStart;
  emu->write_registers(m::reg::kControl, &on, 1);
  emu->write_registers(m::reg::kControl, &start, 1);
  for (auto _ : state) emu->step(1.0);
}
BENCHMARK(BM_DriveModelOneSimSecond)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
