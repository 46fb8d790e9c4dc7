// Runs INSIDE the guest kernel (tests/kernel/guest/gpio.sh): the rig's libgpiod
// backend against a gpio-sim chip whose lines carry the names the rig config
// uses. gpio-sim's sysfs attributes are the "hardware" side: sim_gpioN/value
// is what the rig drives, sim_gpioN/pull is what the e-stop switch does.
// Environment: RIG_GPIO_CHIP (gpiochipN of the sim), lines 0..5 named
// rig-dut-power, rig-estop, rig-lamp-ready, rig-lamp-running, rig-lamp-pass, rig-lamp-fail.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <thread>

#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/gpio/gpiod_lines.hpp"
#include "tests/kernel/gpio_sim.hpp"

using namespace rig;
using namespace rig::gpio;
using rig::kernel_test::GpioSim;

namespace {

GpioSim sim() {
  const char* c = std::getenv("RIG_GPIO_CHIP");
  return GpioSim(c && *c ? c : "gpiochip0");
}

toml::table config(const std::string& extra = "") {
  return cfg::parse_string("chip = \"rig-sim\"\npower = \"rig-dut-power\"\nestop = \"rig-estop\"\n"
                           "lamp_ready = \"rig-lamp-ready\"\nlamp_running = \"rig-lamp-running\"\n"
                           "lamp_pass = \"rig-lamp-pass\"\nlamp_fail = \"rig-lamp-fail\"\n" + extra,
                           "kernel-test.toml");
}

class KernelGpio : public ::testing::Test {
 protected:
  void SetUp() override { sim().pull(1, "pull-up"); }  // e-stop loop closed (active low): released
};

}  // namespace

TEST_F(KernelGpio, LinesAreFoundByNameAndThePowerLineIsSeenOnTheSimulatorSide) {
  auto io = connect_gpio(config());
  EXPECT_NE(io->describe().find("rig-sim"), std::string::npos) << io->describe();
  EXPECT_EQ(sim().value(0), 0);  // the rig starts with the DUT unpowered
  io->set_dut_power(true);
  EXPECT_EQ(sim().value(0), 1);
  EXPECT_TRUE(io->dut_power());
  io->set_lamp(Lamp::Running, true);
  io->set_lamp(Lamp::Pass, true);
  EXPECT_EQ(sim().value(3), 1);
  EXPECT_EQ(sim().value(4), 1);
  EXPECT_EQ(sim().value(5), 0);
  io->set_lamp(Lamp::Pass, false);
  EXPECT_EQ(sim().value(4), 0);
  io->set_dut_power(false);
  EXPECT_EQ(sim().value(0), 0);
  EXPECT_FALSE(io->estop_active());
}

TEST_F(KernelGpio, LinesAreFoundOnAnyChipWithoutTheChipKey) {
  auto io = connect_gpio(cfg::parse_string("power = \"rig-dut-power\"\nestop = \"rig-estop\"\n", "k.toml"));
  io->set_dut_power(true);
  EXPECT_EQ(sim().value(0), 1);
}

TEST_F(KernelGpio, EstopEdgeSwitchesPowerOffWithin50ms) {
  auto io = connect_gpio(config());
  io->set_dut_power(true);
  ASSERT_EQ(sim().value(0), 1);
  std::atomic<bool> handler_saw_power_off{false}, handled{false};
  io->on_estop([&] {
    handler_saw_power_off = sim().value(0) == 0;
    handled = true;
  });
  const double latency = sim().trip_and_time_power_off(1, 0, 2.0);
  for (int i = 0; i < 200 && !handled; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  auto* lines = dynamic_cast<LineRigIo*>(io.get());
  ASSERT_NE(lines, nullptr);
  const double rig_latency = lines->last_estop_reaction_s();
  std::cout << "[ measured ] e-stop edge -> DUT power line low: " << latency * 1e3
            << " ms seen from the switch side; " << rig_latency * 1e3
            << " ms from the kernel's edge timestamp to the rig's power-off (limit 50 ms)" << std::endl;
  EXPECT_GT(rig_latency, 0.0);
  EXPECT_LT(rig_latency, 0.050);
  EXPECT_LT(latency, 0.050);
  EXPECT_TRUE(handled);
  EXPECT_TRUE(handler_saw_power_off);
  EXPECT_TRUE(io->estop_active());
  EXPECT_FALSE(io->dut_power());
  EXPECT_THROW(io->set_dut_power(true), HardwareError);  // interlock holds while the e-stop is open
  EXPECT_EQ(sim().value(0), 0);
  sim().pull(1, "pull-up");  // released
  for (int i = 0; i < 200 && io->estop_active(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_FALSE(io->estop_active());
  io->set_dut_power(true);
  EXPECT_EQ(sim().value(0), 1);
}

TEST_F(KernelGpio, ActiveHighEstopAndActiveLowPower) {
  sim().pull(1, "pull-down");
  auto io = connect_gpio(config("estop_active_low = false\npower_active_low = true\n"));
  EXPECT_FALSE(io->estop_active());
  EXPECT_EQ(sim().value(0), 1);  // active-low power: off = line high
  io->set_dut_power(true);
  EXPECT_EQ(sim().value(0), 0);
  std::atomic<bool> handled{false};
  io->on_estop([&] { handled = true; });
  sim().pull(1, "pull-up");  // active-high switch closes
  for (int i = 0; i < 200 && !handled; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_TRUE(handled);
  EXPECT_EQ(sim().value(0), 1);  // off
}

TEST_F(KernelGpio, StartingWithTheEstopOpenRefusesPower) {
  sim().pull(1, "pull-down");  // active low: open
  auto io = connect_gpio(config());
  EXPECT_TRUE(io->estop_active());
  EXPECT_THROW(io->set_dut_power(true), HardwareError);
  EXPECT_EQ(sim().value(0), 0);
}

TEST_F(KernelGpio, BusyAndUnknownLinesAreHardwareErrorsNamingThem) {
  auto io = connect_gpio(config());
  try {
    connect_gpio(config());
    FAIL() << "second request of the same lines succeeded";
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("rig-dut-power"), std::string::npos) << e.what();
  }
  try {
    connect_gpio(cfg::parse_string("chip = \"rig-sim\"\npower = \"rig-no-such\"\nestop = \"rig-estop\"\n", "k.toml"));
    FAIL();
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("rig-no-such"), std::string::npos) << e.what();
  }
}

// Last in this file (the chip is gone after it): a chip that goes away while the rig watches its
// e-stop line (an unplugged USB expander; here gpio-sim taken down through configfs) is an open
// e-stop: the line's descriptor reports a hang-up without data on every poll, and the watcher,
// which had spun on that (a code review), now takes it as a line that can no longer be read: the
// DUT is switched off and the rig's handler runs.
TEST_F(KernelGpio, ZzAChipThatGoesAwayIsAnOpenEstop) {
  auto io = connect_gpio(config());
  io->set_dut_power(true);
  std::atomic<bool> handled{false};
  io->on_estop([&] { handled = true; });
  {
    std::ofstream live("/sys/kernel/config/gpio-sim/rig/live");
    live << 0;
    live.flush();
    ASSERT_TRUE(live) << "cannot take the gpio-sim chip down";
  }
  for (int i = 0; i < 200 && !handled; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_TRUE(handled);
  EXPECT_TRUE(io->estop_active());
  EXPECT_FALSE(io->dut_power());
}
