// The GPIO safety logic (LineRigIo) with simulated lines: this machine's kernel
// has no GPIO character device, so libgpiod itself is tested in the guest
// kernel against gpio-sim (tests/kernel). The logic under test here is the
// same object the real backend uses.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "plant/emulated/world.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/gpio/gpiod_lines.hpp"
#include "rig/gpio/line_rig_io.hpp"

using namespace rig;
using namespace rig::gpio;

namespace {

struct Rig {
  SimLines* lines;
  std::unique_ptr<LineRigIo> io;
  explicit Rig(bool lamps = true) {
    auto l = std::make_unique<SimLines>(lamps);
    lines = l.get();
    io = std::make_unique<LineRigIo>(std::move(l));
  }
};

// Waits (bounded) for the event thread to have called the handler.
struct Latch {
  std::mutex mu;
  std::condition_variable cv;
  bool fired = false;
  void fire() {
    std::lock_guard lk(mu);
    fired = true;
    cv.notify_all();
  }
  bool wait() {
    std::unique_lock lk(mu);
    return cv.wait_for(lk, std::chrono::seconds(5), [this] { return fired; });
  }
};

}  // namespace

TEST(GpioSafety, EstopEdgeSwitchesPowerOffBeforeTheHandlerRuns) {
  Rig r;
  r.io->set_dut_power(true);
  EXPECT_TRUE(r.lines->level(Output::Power));
  Latch latch;
  bool power_seen_by_handler = true;
  r.io->on_estop([&] {
    power_seen_by_handler = r.lines->level(Output::Power);
    r.lines->note("handler");
    latch.fire();
  });
  r.lines->drive_estop(true);
  ASSERT_TRUE(latch.wait());
  EXPECT_FALSE(power_seen_by_handler);
  EXPECT_FALSE(r.io->dut_power());
  EXPECT_TRUE(r.io->estop_active());
  const auto log = r.lines->log();
  // ... power=1, estop=1, power=0, handler: in this order.
  auto at = [&](const std::string& s) { return std::find(log.begin(), log.end(), s) - log.begin(); };
  ASSERT_LT(at("handler"), static_cast<long>(log.size()));
  EXPECT_LT(at("estop=1"), at("handler"));
  long last_power_off = -1;
  for (long i = 0; i < static_cast<long>(log.size()); ++i)
    if (log[static_cast<std::size_t>(i)] == "power=0" && i > at("estop=1")) last_power_off = i;
  EXPECT_GT(last_power_off, at("estop=1"));
  EXPECT_LT(last_power_off, at("handler"));
}

TEST(GpioSafety, PowerCannotBeSwitchedOnDuringEstopUntilReleased) {
  Rig r;
  Latch latch;
  r.io->on_estop([&] { latch.fire(); });
  r.lines->drive_estop(true);
  ASSERT_TRUE(latch.wait());
  try {
    r.io->set_dut_power(true);
    FAIL();
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("e-stop"), std::string::npos);
  }
  EXPECT_FALSE(r.lines->level(Output::Power));
  r.lines->drive_estop(false);
  for (int i = 0; i < 500 && r.io->estop_active(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  EXPECT_FALSE(r.io->estop_active());
  r.io->set_dut_power(true);
  EXPECT_TRUE(r.lines->level(Output::Power));
}

TEST(GpioSafety, StartsUnpoweredAndRefusesWhenEstopAlreadyActive) {
  auto l = std::make_unique<SimLines>();
  SimLines* lines = l.get();
  lines->set(Output::Power, true);  // left on by a previous program
  lines->drive_estop(true);         // and the interlock is open
  LineRigIo io(std::move(l));
  EXPECT_FALSE(lines->level(Output::Power));
  EXPECT_TRUE(io.estop_active());
  EXPECT_THROW(io.set_dut_power(true), HardwareError);
}

TEST(GpioSafety, LampsDriveTheirLinesAndMissingLampsAreIgnored) {
  Rig r;
  r.io->set_lamp(Lamp::Running, true);
  r.io->set_lamp(Lamp::Pass, true);
  r.io->set_lamp(Lamp::Pass, false);
  EXPECT_TRUE(r.lines->level(Output::LampRunning));
  EXPECT_FALSE(r.lines->level(Output::LampPass));
  EXPECT_FALSE(r.lines->level(Output::LampReady));
  Rig bare(false);
  bare.io->set_lamp(Lamp::Fail, true);  // not wired: no effect, no error
  EXPECT_FALSE(bare.lines->level(Output::LampFail));
}

TEST(GpioSafety, LeavingWakesTheWatcherInsteadOfWaitingOutItsTimeout) {
  // A driver whose wait ignores its timeout and ends only when woken (or after a minute). The
  // test destroys the rig once the watcher sleeps in it: the destructor must wake it, or the
  // wait ends by its minute and the test fails.
  struct Shared {
    std::mutex m;
    std::condition_variable cv;
    bool waiting = false, woken = false, timed_out = false;
  };
  struct Sleepy final : LineDriver {
    Shared& sh;
    explicit Sleepy(Shared& s) : sh(s) {}
    bool has(Output o) const override { return o == Output::Power; }
    void set(Output, bool) override {}
    bool estop_active() override { return false; }
    std::optional<bool> wait_estop_edge(std::chrono::milliseconds) override {
      std::unique_lock lk(sh.m);
      sh.waiting = true;
      sh.cv.notify_all();
      if (!sh.cv.wait_for(lk, std::chrono::minutes(1), [this] { return sh.woken; })) sh.timed_out = true;
      return std::nullopt;
    }
    void wake() override {
      {
        std::lock_guard lk(sh.m);
        sh.woken = true;
      }
      sh.cv.notify_all();
    }
    std::string describe() const override { return "sleepy lines"; }
  };
  Shared sh;
  {
    LineRigIo io(std::make_unique<Sleepy>(sh));
    std::unique_lock lk(sh.m);
    sh.cv.wait(lk, [&] { return sh.waiting; });
  }
  EXPECT_TRUE(sh.woken);
  EXPECT_FALSE(sh.timed_out);
}

TEST(GpioSafety, SimulatedLinesWokenStillHandOverAPendingEdge) {
  SimLines lines;
  lines.drive_estop(true);
  lines.wake();
  EXPECT_EQ(lines.wait_estop_edge(std::chrono::milliseconds(0)), std::optional<bool>(true));
  EXPECT_EQ(lines.wait_estop_edge(std::chrono::hours(1)), std::nullopt);  // woken: no wait
}

TEST(GpioSafety, DestructionLeavesTheDutUnpowered) {
  // The lines outlive the RigIo here (shared), so their last state can be checked.
  struct Shared final : LineDriver {
    std::shared_ptr<SimLines> s;
    explicit Shared(std::shared_ptr<SimLines> p) : s(std::move(p)) {}
    bool has(Output o) const override { return s->has(o); }
    void set(Output o, bool a) override { s->set(o, a); }
    bool estop_active() override { return s->estop_active(); }
    std::optional<bool> wait_estop_edge(std::chrono::milliseconds t) override { return s->wait_estop_edge(t); }
    std::string describe() const override { return s->describe(); }
  };
  auto lines = std::make_shared<SimLines>();
  {
    LineRigIo io(std::make_unique<Shared>(lines));
    io.set_dut_power(true);
    EXPECT_TRUE(lines->level(Output::Power));
  }
  EXPECT_FALSE(lines->level(Output::Power));
  EXPECT_EQ(lines->log().back(), "power=0");
}

// The emulated plant has no GPIO logic of its own: its lines sit behind the same LineRigIo
// as the rig's, so an injected e-stop (`rig run --inject estop@T`) exercises the shipped
// path. Only LineRigIo refuses power while the e-stop is active and measures its reaction.
TEST(GpioSafety, EmulatedPlantEstopGoesThroughLineRigIo) {
  toml::table cfg;
  cfg.insert("seed", 1);
  plant::EmulatedPlant w(cfg);
  LineRigIo& io = w.io();
  io.set_dut_power(true);
  EXPECT_TRUE(w.lines().level(Output::Power));
  bool power_in_handler = true;
  double t_handler = -1;
  io.on_estop([&] {
    power_in_handler = w.lines().level(Output::Power);
    t_handler = w.clock().now_s();
    w.lines().note("handler");
  });
  w.trip_estop_at(0.5);
  w.clock().sleep_for(1.0, {});
  // The world waited for the watcher: the handler ran within the slice of the edge.
  EXPECT_GE(t_handler, 0.49);
  EXPECT_LE(t_handler, 0.5 + 1e-9);
  EXPECT_FALSE(power_in_handler);
  EXPECT_FALSE(io.dut_power());
  EXPECT_TRUE(io.estop_active());
  EXPECT_GT(io.last_estop_reaction_s(), 0.0);
  EXPECT_THROW(io.set_dut_power(true), HardwareError);
  const auto log = w.lines().log();
  const auto at = [&](const std::string& e) { return std::find(log.begin(), log.end(), e) - log.begin(); };
  EXPECT_LT(at("estop=1"), at("handler"));
  EXPECT_EQ(log[static_cast<std::size_t>(at("handler")) - 1], "power=0");
}

TEST(GpioConfig, ParsesNamesAndDefaults) {
  const auto t = cfg::parse_string(R"(
chip = "gpio-sim-rig"
power = "dut-power"
estop = "estop"
lamp_ready = "lamp-ready"
estop_active_low = false
)", "rig.toml");
  const GpioConfig c = parse_gpio_config(t);
  EXPECT_EQ(c.chip, "gpio-sim-rig");
  EXPECT_EQ(c.power, "dut-power");
  EXPECT_EQ(c.estop, "estop");
  EXPECT_EQ(c.lamp_ready, "lamp-ready");
  EXPECT_TRUE(c.lamp_pass.empty());
  EXPECT_FALSE(c.estop_active_low);
  EXPECT_FALSE(c.power_active_low);
}

TEST(GpioConfig, MistakesNameFileAndLine) {
  auto expect_config_error = [](const char* text, const char* needle) {
    try {
      parse_gpio_config(cfg::parse_string(text, "hw.toml"));
      ADD_FAILURE() << "no error for: " << text;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("hw.toml:"), std::string::npos) << e.what();
    }
  };
  expect_config_error("power = \"p\"\n", "estop");
  expect_config_error("power = \"p\"\nestop = \"e\"\nlamp_redy = \"x\"\n",
                      "hw.toml:3:1: unknown key 'lamp_redy' in [gpio] (expected");  // not "[[gpio]]"
  expect_config_error("power = \"p\"\nestop = \"p\"\n", "hw.toml:2:9: [gpio] estop names the same line as power ('p')");
  // Every line has one job (a review: a lamp on the e-stop input passed the dry run).
  expect_config_error("power = \"p\"\nestop = \"e\"\nlamp_pass = \"e\"\n",
                      "hw.toml:3:13: [gpio] lamp_pass names the same line as estop ('e')");
  expect_config_error("power = \"p\"\nestop = \"e\"\nlamp_fail = \"f\"\nlamp_pass = \"f\"\n",
                      "hw.toml:3:13: [gpio] lamp_fail names the same line as lamp_pass ('f')");
  expect_config_error("power = 3\nestop = \"e\"\n", "power");
}

TEST(GpioConfig, MissingChipOrLineIsAHardwareErrorNamingIt) {
  // On the build host there is no GPIO chip at all; in the guest there is no
  // chip of this name either. Either way: HardwareError naming the key.
  const auto t = cfg::parse_string("chip = \"no-such-chip\"\npower = \"p\"\nestop = \"e\"\n", "hw.toml");
  try {
    connect_gpio(t);
    FAIL();
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("no-such-chip"), std::string::npos) << e.what();
  }
  const auto t2 = cfg::parse_string("power = \"rig-test-no-such-line\"\nestop = \"e\"\n", "hw.toml");
  try {
    connect_gpio(t2);
    FAIL();
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("rig-test-no-such-line"), std::string::npos) << e.what();
  }
}
