// [dut] of the hardware file, the SocketCAN backend's behaviour on a host
// without it, and the emulated plant's one DUT path.
#include <gtest/gtest.h>

#include "firmware_link/connect.hpp"
#include "firmware_link/socketcan.hpp"
#include "plant/emulated/world.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"

using namespace rig;
using namespace rig::link;

TEST(DutConfig, OptionsFromTheHardwareFile) {
  const auto t = cfg::parse_string("can = \"can0\"\nsilence_ms = 80\ncommand_timeout_ms = 40\ncommand_attempts = 5\n",
                                   "hw.toml");
  const LinkOptions o = link_options(t);
  EXPECT_DOUBLE_EQ(o.silence_s, 0.08);
  EXPECT_DOUBLE_EQ(o.command_timeout_s, 0.04);
  EXPECT_EQ(o.command_attempts, 5);
  EXPECT_EQ(o.reorder_window, 8u);
  EXPECT_TRUE(o.loop_test) << "the loop test is asked for unless the hardware file says otherwise";
  EXPECT_FALSE(link_options(cfg::parse_string("can = \"can0\"\nloop_test = false\n", "hw.toml")).loop_test);
}

TEST(DutConfig, MistakesAreConfigErrorsWithPlace) {
  RealClock clock;
  auto expect_err = [&](const char* text, const char* needle) {
    try {
      connect_dut(cfg::parse_string(text, "hw.toml"), clock);
      ADD_FAILURE() << text;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("hw.toml:"), std::string::npos) << e.what();
    }
  };
  expect_err("silence_ms = 100\n", "can");
  expect_err("can = \"vcan0\"\nsilense_ms = 100\n", "unknown key 'silense_ms' in [dut] (");  // it said "[[dut]]"
  expect_err("can = \"vcan0\"\nsilence_ms = -1\n", "silence_ms");
  expect_err("can = \"an-interface-name-too-long\"\n", "network interface");
  expect_err("can = \"vcan0\"\nloop_test = \"no\"\n", "loop_test");
}

TEST(SocketCan, UnavailableOrUnknownInterfaceIsAHardwareErrorNamingIt) {
  // The build host's kernel has no AF_CAN; the guest kernel has it but no such
  // interface. Both must fail the same way: HardwareError naming the interface.
  try {
    SocketCanTransport t("rigtest9");
    FAIL();
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("rigtest9"), std::string::npos) << e.what();
    if (!socketcan_available()) {
      EXPECT_NE(std::string(e.what()).find("no SocketCAN"), std::string::npos) << e.what();
    }
  }
}

// The emulated DUT has one path, the CAN link: a profile that still selects the removed
// direct link (or names `link` at all) is refused with its file and line, not run another way.
TEST(EmulatedPlantConfig, TheRemovedLinkKeyIsAnErrorNamingFileAndLine) {
  for (const char* value : {"\"direct\"", "\"can\""}) {
    const auto t = cfg::parse_string(std::string("seed = 3\nlink = ") + value + "\n", "old.toml");
    try {
      plant::EmulatedPlant w(t);
      ADD_FAILURE() << "no error for link = " << value;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("old.toml:2"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("link"), std::string::npos) << e.what();
    }
  }
}
