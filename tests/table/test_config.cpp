// Configuration of the client ([table] of a hardware file) and of the emulator
// ([plant.table] of a profile): every mistake names file:line.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "helpers.hpp"
#include "rig/core/clock.hpp"
#include "rig/modbus/table_client.hpp"

namespace rig::table_test {
namespace {

namespace m = rig::modbus;

template <class F>
std::string config_error(F f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no ConfigError)";
}

TEST(TableConfig, EndpointsParse) {
  EXPECT_EQ(m::parse_endpoint("tcp:10.0.0.5:1502").str(), "tcp:10.0.0.5:1502");
  EXPECT_EQ(m::parse_endpoint("localhost:502").str(), "tcp:localhost:502");
  EXPECT_EQ(m::parse_endpoint("rtu:/dev/ttyUSB0").str(), "rtu:/dev/ttyUSB0,19200,E,8,1");
  EXPECT_EQ(m::parse_rtu("/dev/ttyUSB0,115200,N,8,1").str(), "rtu:/dev/ttyUSB0,115200,N,8,1");
  EXPECT_EQ(m::parse_rtu("/dev/ttyS1,9600").str(), "rtu:/dev/ttyS1,9600,E,8,1");
  EXPECT_NE(config_error([] { m::parse_endpoint("tcp:host"); }).find("must be HOST:PORT"), std::string::npos);
  EXPECT_NE(config_error([] { m::parse_endpoint("tcp:host:http"); }).find("port 'http' is not a number"),
            std::string::npos);
  // A port, baud rate or bit count is decimal digits without a sign or leading zero, like every
  // number on the command line: "015610" is a typo, not port 15610.
  EXPECT_EQ(config_error([] { m::parse_endpoint("host:015610"); }),
            "'host:015610': port '015610' is not a decimal whole number (no leading zero)");
  EXPECT_EQ(config_error([] { m::parse_endpoint("host:+502"); }), "'host:+502': port '+502' is not a number");
  EXPECT_EQ(config_error([] { m::parse_endpoint("host:-1"); }), "'host:-1': port '-1' is not a number");
  EXPECT_EQ(config_error([] { m::parse_endpoint("host:99999999999"); }), "'host:99999999999': port '99999999999' out of range");
  EXPECT_EQ(config_error([] { m::parse_rtu("/dev/ttyS1,09600"); }),
            "'/dev/ttyS1,09600': baud rate '09600' is not a decimal whole number (no leading zero)");
  EXPECT_EQ(m::parse_endpoint("host:0").port, 0);
  // A speed the serial port has not: libmodbus would run it at 9600 without a word (a review).
  EXPECT_NE(config_error([] { m::parse_rtu("/dev/ttyS1,11520"); }).find("baud rate 11520 is not a serial port speed"),
            std::string::npos);
  EXPECT_EQ(m::parse_rtu("/dev/ttyS1,921600").baud, 921600);
  EXPECT_NE(config_error([] { m::parse_rtu("/dev/ttyS1,9600,X,8,1"); }).find("parity must be N, E or O"),
            std::string::npos);
  EXPECT_EQ(m::parse_endpoint("tcp:[fe80::1]:502").host, "fe80::1");
  EXPECT_EQ(m::parse_endpoint("[::1]:502").str(), "tcp:[::1]:502");  // str() parses back
  EXPECT_EQ(m::parse_endpoint("fd00::10:502").host, "fd00::10");       // unbracketed, as before
  EXPECT_EQ(m::parse_endpoint("tcp:[fe80::1%lo]:502").host, "fe80::1%lo");  // a link-local zone
  EXPECT_NE(config_error([] { m::parse_endpoint("udp:10.0.0.5:502"); }).find("'udp:10.0.0.5' is not a host name"),
            std::string::npos);
  EXPECT_NE(config_error([] { m::parse_endpoint("zz zz:502"); }).find("'zz zz' is not a host name"),
            std::string::npos);
  // Hex digits and colons that are no IPv6 address are named too, not left to connect().
  EXPECT_NE(config_error([] { m::parse_endpoint("add:10.0.0.5:502"); }).find("'add:10.0.0.5' is not a host name"),
            std::string::npos);
  EXPECT_NE(config_error([] { m::parse_endpoint("tcp:[fe80:::1]:502"); }).find("'[fe80:::1]' is not a host name"),
            std::string::npos);
  EXPECT_NE(config_error([] { m::parse_endpoint("tcp:[fe80::1%]:502"); }).find("is not a host name"), std::string::npos);
  EXPECT_EQ(m::parse_endpoint("tcp:[::ffff:10.0.0.5]:502").host, "::ffff:10.0.0.5");  // IPv4-mapped
  // Modbus RTU is 8 data bits (7 is Modbus ASCII's): refused, not left to a drive that never answers.
  EXPECT_EQ(config_error([] { m::parse_rtu("/dev/ttyS1,9600,N,7,2"); }),
            "Modbus RTU port '/dev/ttyS1,9600,N,7,2': 7 data bits: Modbus RTU needs 8");
  EXPECT_EQ(m::parse_rtu("/dev/ttyS1,9600,N,8,2").str(), "rtu:/dev/ttyS1,9600,N,8,2");
  // Port 0 stays a server's "any port" (rig plant serve, the tests' servers); a client's [table]
  // refuses it at its line (it was exit 4, "cannot connect").
  EXPECT_EQ(m::parse_endpoint("tcp:127.0.0.1:0").port, 0);
  const std::string e = config_error([] { m::check_table_config(cfg::parse_string("modbus = \"127.0.0.1:0\"\n", "hw.toml")); });
  EXPECT_EQ(e, "hw.toml:1:10: 'modbus' = '127.0.0.1:0': port 0 is no drive's port (1..65535)");
}

// What the station's table lock is keyed on: a TCP endpoint with its unit; a serial device by its
// resolved name, whatever its line settings and unit (a re-test: a by-id link, or another baud
// rate, took a second lock on one port).
TEST(TableConfig, TheTableIdentityNamesOneSerialDeviceOnce) {
  EXPECT_EQ(m::table_identity(cfg::parse_string("modbus = \"127.0.0.1:1502\"\nunit = 3\n", "hw.toml")),
            "tcp:127.0.0.1:1502 unit 3");
  // One TCP host by any of its names: a name is keyed by the least IPv4 address it resolves to
  // ("localhost" and "127.0.0.1" were two keys: two terminals could command one drive at once).
  for (const char* host : {"localhost", "LOCALHOST", "LocalHost", "127.1", "0.0.0.0", "0"})
    EXPECT_EQ(m::table_identity(cfg::parse_string("modbus = \"" + std::string(host) + ":1502\"\nunit = 3\n", "hw.toml")),
              "tcp:127.0.0.1:1502 unit 3")
        << host;
  EXPECT_EQ(m::table_identity(cfg::parse_string("modbus = \"[::1]:1502\"\n", "hw.toml")), "tcp:[::1]:1502 unit 1");
  EXPECT_EQ(m::table_identity(cfg::parse_string("modbus = \"[::]:1502\"\n", "hw.toml")), "tcp:[::1]:1502 unit 1");
  EXPECT_EQ(m::table_identity(cfg::parse_string("modbus = \"[::ffff:10.0.0.7]:502\"\n", "hw.toml")),
            "tcp:10.0.0.7:502 unit 1");
  const std::string dir = testing::TempDir() + "/tty-identity";
  std::filesystem::create_directories(dir);
  const std::string dev = dir + "/ttyFAKE0", link = dir + "/by-id-link";
  std::ofstream(dev) << "";
  std::filesystem::remove(link);
  std::filesystem::create_symlink(dev, link);
  const std::string canonical = std::filesystem::canonical(dev).string();
  EXPECT_EQ(m::table_identity(cfg::parse_string("rtu = \"" + dev + "\"\n", "hw.toml")), "rtu:" + canonical);
  EXPECT_EQ(m::table_identity(cfg::parse_string("rtu = \"" + link + ",115200,N,8,1\"\nunit = 7\n", "hw.toml")),
            "rtu:" + canonical);
}

TEST(TableConfig, HardwareTableKeysAreChecked) {
  RealClock clock;
  const toml::table typo = cfg::parse_string("modbus = \"127.0.0.1:1\"\ntolerance = 0.01\n", "hw.toml");
  const std::string e1 = config_error([&] { m::connect_table(typo, clock); });
  EXPECT_NE(e1.find("hw.toml:2:"), std::string::npos) << e1;
  EXPECT_NE(e1.find("unknown key 'tolerance'"), std::string::npos) << e1;
  const toml::table both = cfg::parse_string("modbus = \"127.0.0.1:1\"\nrtu = \"/dev/ttyS0\"\n", "hw.toml");
  EXPECT_NE(config_error([&] { m::connect_table(both, clock); }).find("exactly one of"), std::string::npos);
  const toml::table bad_ep = cfg::parse_string("unit = 1\nmodbus = \"nowhere\"\n", "hw.toml");
  const std::string e3 = config_error([&] { m::connect_table(bad_ep, clock); });
  EXPECT_NE(e3.find("hw.toml:2:"), std::string::npos) << e3;
  const toml::table bad_unit = cfg::parse_string("modbus = \"127.0.0.1:1\"\nunit = 300\n", "hw.toml");
  EXPECT_NE(config_error([&] { m::connect_table(bad_unit, clock); }).find("hw.toml:2:"), std::string::npos);
  const toml::table ok = cfg::parse_string(
      "tolerance_deg = 0.002\nsettle_s = 2.0\nvelocity_dps = 12.5\nu10_deg = 0.0\nu20_deg = 180.0\n", "hw.toml");
  const m::TableOptions o = m::table_options_from_toml(ok);
  EXPECT_DOUBLE_EQ(o.tolerance_deg, 0.002);
  EXPECT_DOUBLE_EQ(o.settle_s, 2.0);
  ASSERT_TRUE(o.velocity_dps.has_value());
  EXPECT_DOUBLE_EQ(*o.velocity_dps, 12.5);
  EXPECT_FALSE(o.accel_dps2.has_value());
}

TEST(TableConfig, PlantTableKeysAreChecked) {
  const std::string e1 = config_error([] { emulator("velocity_dps = 10.0\nspeed = 3\n"); });
  EXPECT_NE(e1.find("test-table.toml:2:"), std::string::npos) << e1;
  EXPECT_NE(e1.find("unknown key 'speed' in [plant.table]"), std::string::npos) << e1;
  const std::string e2 = config_error([] { emulator("fault = \"gremlins\"\n"); });
  EXPECT_NE(e2.find("test-table.toml:1:"), std::string::npos) << e2;
  EXPECT_NE(e2.find("unknown table fault 'gremlins'"), std::string::npos) << e2;
  const std::string e3 = config_error([] { emulator("velocity_dps = 500.0\n"); });
  EXPECT_NE(e3.find("out of range"), std::string::npos) << e3;
  // SETTLE_TIME is at most 10000 ms: a longer settle_s served a map the rig's client refused.
  const std::string e4 = config_error([] { emulator("settle_s = 20\n"); });
  EXPECT_NE(e4.find("test-table.toml:1:"), std::string::npos) << e4;
  EXPECT_NE(e4.find("out of range"), std::string::npos) << e4;
  EXPECT_NO_THROW(emulator("settle_s = 10\n"));
  const plant::TableParams p = plant::table_params_from_toml(nullptr);
  EXPECT_DOUBLE_EQ(p.velocity_dps, 30.0);
}

}  // namespace
}  // namespace rig::table_test
