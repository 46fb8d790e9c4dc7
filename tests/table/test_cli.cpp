// `rig table status|home|move|stop|quick-stop|reset` against the emulator on a
// real wire, checking output and the documented exit codes (docs/contracts.md).
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <pty.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <thread>

#include "helpers.hpp"
#include "plant/table/table_server.hpp"

namespace rig::table_test {
namespace {

namespace m = rig::modbus;

// The station lock's folder for every rig this binary starts: its own, not /run/lock, which the
// runs' ports (each a new one) filled with lock files (a re-test).
// Made before main (so before the private TMPDIR of tests/support/private_tmp.cpp), hence removed
// at exit: ctest starts this binary once per test and once to list them, and each left a folder.
struct PrivateLockDir {
  std::string dir = std::filesystem::temp_directory_path() / ("rig-table-locks-" + std::to_string(::getpid()));
  PrivateLockDir() {
    std::filesystem::create_directories(dir);
    ::setenv("RIG_LOCK_DIR", dir.c_str(), 1);
  }
  ~PrivateLockDir() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
};
const PrivateLockDir kPrivateLockDir;

class RigTable : public ::testing::Test {
 protected:
  void SetUp() override {
    server_.start();
    where_ = "--modbus " + server_.endpoint().substr(4);
  }
  int rig(const std::string& args, std::string& out) { return run(std::string(RIG_BIN) + " table " + args, out); }
  // Homes the table, slows its profile (so a move is still running when a signal lands) and
  // starts `rig table move 300` as its own process (after `prefix`, e.g. nohup), returning once
  // the table moves.
  void start_slow_move(const std::vector<std::string>& prefix, std::unique_ptr<Child>& child, int& fd) {
    std::string out;
    ASSERT_EQ(rig(where_ + " home", out), 0) << out;
    ASSERT_EQ(run("mbpoll -m tcp -p " + server_.endpoint().substr(server_.endpoint().rfind(':') + 1) +
                      " -a 1 -0 -1 -t 4:int -B -r 10 127.0.0.1 20000",
                  out),
              0)
        << out;
    std::vector<std::string> argv = prefix;
    for (const std::string& a : {std::string(RIG_BIN), std::string("table"), std::string("--modbus"),
                                 server_.endpoint().substr(4), std::string("move"), std::string("300")})
      argv.push_back(a);
    child = std::make_unique<Child>(argv, &fd);
    for (int i = 0; i < 2000 && !emu_->snapshot().moving; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    ASSERT_TRUE(emu_->snapshot().moving);
  }
  std::unique_ptr<plant::TableEmulator> emu_ = emulator(kFastTable);
  plant::TableServer server_{*emu_, "tcp:127.0.0.1:0"};
  std::string where_;
};

TEST_F(RigTable, StatusHomeMove) {
  std::string out;
  ASSERT_EQ(rig(where_ + " status", out), 0) << out;
  EXPECT_NE(out.find("alarm      none"), std::string::npos) << out;
  EXPECT_NE(out.find("modbus " + server_.endpoint() + " unit 1"), std::string::npos) << out;
  ASSERT_EQ(rig(where_ + " home", out), 0) << out;
  EXPECT_NE(out.find("homed"), std::string::npos) << out;
  ASSERT_EQ(rig(where_ + " move 123.25", out), 0) << out;
  EXPECT_NE(out.find("actual     123.2500°"), std::string::npos) << out;
  EXPECT_NE(out.find("in-position"), std::string::npos) << out;
  EXPECT_NE(out.find("target     123.2500°\n"), std::string::npos) << "at its target, nothing said: " << out;
  EXPECT_NEAR(emu_->actual_angle_deg(), 123.25, 0.005);
  ASSERT_EQ(rig(where_ + " status --json", out), 0) << out;
  EXPECT_NE(out.find("\"homed\": true"), std::string::npos) << out;
  EXPECT_NE(out.find("\"at_target\": true"), std::string::npos) << out;
  // A stop is one urgent read of the status block and the CONTROL write: a status read before it
  // added a request to every stop and two timeouts to one on a silent link (a review).
  const uint64_t before = server_.requests_served();
  ASSERT_EQ(rig(where_ + " stop", out), 0) << out;
  EXPECT_EQ(server_.requests_served() - before, 2u);
  ASSERT_EQ(rig(where_ + " quick-stop", out), 0) << out;
  EXPECT_NE(out.find("quick stop sent"), std::string::npos) << out;
}

// `--drive cia402` at this rig-v1 table (the wrong drive in a hardware file): every command is
// refused before a write, exit 4, naming the statusword that is no CiA 402 state; the quick stop
// and the halt (0x0002 and 0x0100: START or HALT with SERVO_ON clear here, which dropped the servo
// before) are not sent, and the table holds where it was, its servo on.
TEST_F(RigTable, ACia402ClientAtThisTableIsRefusedAndSendsNothing) {
  std::string out;
  const std::string c4 = where_ + " --drive cia402 --drive-map " + RIG_SOURCE_DIR + "/drives/generic-cia402.toml ";
  ASSERT_EQ(rig(where_ + " status", out), 0) << out;  // not homed yet, said so (a review: "ready" alone)
  EXPECT_NE(out.find("NOT-HOMED"), std::string::npos) << out;
  ASSERT_EQ(rig(where_ + " home", out), 0) << out;
  ASSERT_EQ(rig(where_ + " status", out), 0) << out;
  EXPECT_EQ(out.find("NOT-HOMED"), std::string::npos) << out;
  ASSERT_EQ(run("mbpoll -m tcp -p " + server_.endpoint().substr(server_.endpoint().rfind(':') + 1) +
                    " -a 1 -0 -1 -t 4:int -B -r 8 127.0.0.1 900000",
                out),
            0)
      << out;  // TARGET_POS 90°: where a START would take it
  for (const char* cmd : {"status", "home", "move 45", "reset"}) {
    EXPECT_EQ(rig(c4 + cmd, out), 4) << cmd << ": " << out;
    EXPECT_NE(out.find("statusword (0x6041) at holding register 1 reads 0x"), std::string::npos) << out;
    EXPECT_NE(out.find("none of the CiA 402 states (IEC 61800-7-201): not a CiA 402 drive"), std::string::npos) << out;
    EXPECT_NE(out.find("; nothing sent"), std::string::npos) << out;
  }
  EXPECT_EQ(rig(c4 + "quick-stop", out), 4) << out;
  EXPECT_NE(out.find("quick stop not sent (the table may still be moving): statusword (0x6041)"), std::string::npos) << out;
  EXPECT_EQ(rig(c4 + "stop", out), 4) << out;
  EXPECT_NE(out.find("halt not sent (the table may still be moving): statusword (0x6041)"), std::string::npos) << out;
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_FALSE(emu_->snapshot().moving);
  EXPECT_NEAR(emu_->actual_angle_deg(), 0.0, 0.005);
  ASSERT_EQ(rig(where_ + " status", out), 0) << out;
  EXPECT_NE(out.find("servo-on"), std::string::npos) << out;  // the halt that was not sent kept it
}

// On a terminal a home or a move shows the angle the drive reads while the table turns, on one
// line that is cleared before the status is printed; piped (as in every other test here), none of it.
TEST_F(RigTable, OnATerminalTheTurningTableShowsItsAngle) {
  std::string out;
  ASSERT_EQ(rig(where_ + " home", out), 0) << out;
  EXPECT_EQ(out.find("table at"), std::string::npos) << out;
  const std::string ep = server_.endpoint().substr(4);
  int fd = -1;
  const pid_t pid = ::forkpty(&fd, nullptr, nullptr, nullptr);
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::execl(RIG_BIN, RIG_BIN, "table", "--modbus", ep.c_str(), "move", "300", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  std::string seen;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  for (;;) {
    pollfd p{fd, POLLIN, 0};
    if (std::chrono::steady_clock::now() > deadline || ::poll(&p, 1, 100) < 0) break;
    if (!(p.revents & (POLLIN | POLLHUP))) continue;
    char buf[4096];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n <= 0) break;  // EIO once the child has closed the terminal
    seen.append(buf, static_cast<std::size_t>(n));
  }
  int st = 0;
  ::waitpid(pid, &st, 0);
  ::close(fd);
  ASSERT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0) << seen;
  // 290 degrees at 360 deg/s: about a second, so several readings at five a second.
  std::size_t lines = 0;
  for (std::size_t at = seen.find("moving to 300.0000°: table at "); at != std::string::npos;
       at = seen.find("moving to 300.0000°: table at ", at + 1))
    ++lines;
  EXPECT_GE(lines, 2u) << seen;
  const std::size_t last = seen.rfind("table at "), cleared = seen.rfind("\r\x1b[K"),
                    status = seen.find("actual     300.0000°");
  ASSERT_NE(status, std::string::npos) << seen;
  EXPECT_LT(last, cleared) << seen;
  EXPECT_LT(cleared, status) << seen;
}

// A home, a move or a reset prints where the table ended: started with stdout closed it turned
// the table and then exited 2, read as nothing done (a technician's re-test). Refused before
// anything is sent; a stop still goes out.
TEST_F(RigTable, AMotionWithStdoutClosedIsRefusedBeforeAnythingIsSent) {
  const std::string err = std::filesystem::temp_directory_path() / ("rig-closed-" + std::to_string(::getpid()));
  std::string out;
  for (const char* command : {"home", "move 10", "reset"}) {
    EXPECT_EQ(run("(" + std::string(RIG_BIN) + " table " + where_ + " " + command + " >&- 2>" + err + ")", out), 2)
        << command;
    std::ifstream in(err);
    const std::string said((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(said.find(std::string("rig table ") + (std::string(command) == "move 10" ? "move 10.0000°" : command) +
                        ": standard output is closed (the command was started with it closed, >&-): it prints where "
                        "the table ended; nothing sent"),
              std::string::npos)
        << said;
    EXPECT_FALSE(emu_->snapshot().homed) << command;
    EXPECT_FALSE(emu_->snapshot().moving) << command;
    EXPECT_FALSE(emu_->snapshot().servo_on) << command;
  }
  // /dev/full likewise (`> /dev/full` homed the table, then exit 2: a review).
  for (const char* command : {"home", "move 10"}) {
    EXPECT_EQ(run("(" + std::string(RIG_BIN) + " table " + where_ + " " + command + " > /dev/full 2>" + err + ")", out),
              2)
        << command;
    std::ifstream in(err);
    const std::string said((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(said.find(": standard output is /dev/full: it prints where the table ended; nothing sent"),
              std::string::npos)
        << said;
    EXPECT_FALSE(emu_->snapshot().homed) << command;
    EXPECT_FALSE(emu_->snapshot().servo_on) << command;
  }
  EXPECT_EQ(run("(" + std::string(RIG_BIN) + " table " + where_ + " stop >&- 2>" + err + ")", out), 0)
      << "a stop is never refused";
  EXPECT_EQ(run("(" + std::string(RIG_BIN) + " table " + where_ + " quick-stop > /dev/full 2>" + err + ")", out), 0)
      << "the stop is its result, exit 0 when delivered; its printed line only confirms it";
  // A reader gone is no SIGPIPE's 141 after the stop went out (a code review).
  EXPECT_EQ(run("bash -c 'set -o pipefail; sleep 0.2 | true; " + std::string(RIG_BIN) + " table " + where_ + " stop 2>" +
                    err + " | true'",
                out),
            0)
      << out;
  // A hardware file named `stop` is no stop: the move is refused as any move (a word scan took it
  // for one, and the table turned with nothing printed: a code review).
  const std::string folder = std::filesystem::temp_directory_path() / ("rig-stopfile-" + std::to_string(::getpid()));
  std::filesystem::create_directories(folder);
  std::ofstream(folder + "/stop") << "[table]\nmodbus = \"" << server_.endpoint() << "\"\n";
  EXPECT_EQ(run("(cd " + folder + " && " + std::string(RIG_BIN) + " table --hardware stop move 10 >&- 2>" + err + ")", out),
            2);
  EXPECT_FALSE(emu_->snapshot().servo_on);
  std::filesystem::remove_all(folder);
  std::filesystem::remove(err);
}

TEST_F(RigTable, FaultsExitWithFourAndSayWhat) {
  std::string out;
  EXPECT_EQ(rig(where_ + " move 90", out), 4) << out;
  EXPECT_NE(out.find("move to 90.0000°: table not homed"), std::string::npos) << out;
  // Exit 4, but named as a state, not a fault (a technician's review: "hardware fault" read as a
  // broken drive).
  EXPECT_NE(out.find("rig: not ready: move to 90.0000°: table not homed"), std::string::npos) << out;
  // Outside the travel limits is the command's mistake, homed or not (it was exit 4 unhomed).
  EXPECT_EQ(rig(where_ + " move 1000", out), 2) << out;
  EXPECT_NE(out.find("outside the drive's travel limits [-190.0000°, 370.0000°]; nothing sent"), std::string::npos)
      << out;  // said as every refusal before a write is (a technician's re-test)
  ASSERT_EQ(rig(where_ + " home", out), 0) << out;
  emu_->inject(SimFault::kDriveFault, 0.5);
  EXPECT_EQ(rig(where_ + " move 180", out), 4) << out;
  EXPECT_NE(out.find("rig: hardware fault: move to 180.0000°: alarm 0x0040 drive fault (power stage) at"),
            std::string::npos)
      << out;
  ASSERT_EQ(rig(where_ + " status", out), 0) << out;
  EXPECT_NE(out.find("alarm      0x0040 drive fault"), std::string::npos) << out;
  ASSERT_EQ(rig(where_ + " reset", out), 0) << out;
  EXPECT_NE(out.find("alarm      none"), std::string::npos) << out;
  ASSERT_EQ(rig(where_ + " status --json", out), 0) << out;
  EXPECT_NE(out.find("\"limit_pos\": false"), std::string::npos) << out;
  // On an over-travel switch the status says which one (a review: "homed ALARM" alone did not
  // say which way to move off it).
  emu_->inject(SimFault::kOverTravel, 0.5);
  EXPECT_EQ(rig(where_ + " move 350", out), 4) << out;
  ASSERT_EQ(rig(where_ + " status", out), 0) << out;
  EXPECT_NE(out.find(" ALARM LIMIT-POS"), std::string::npos) << out;
  ASSERT_EQ(rig(where_ + " status --json", out), 0) << out;
  EXPECT_NE(out.find("\"limit_pos\": true"), std::string::npos) << out;
  EXPECT_NE(out.find("\"limit_neg\": false"), std::string::npos) << out;
  ASSERT_EQ(rig(where_ + " reset", out), 0) << out;
  EXPECT_EQ(rig("--modbus 127.0.0.1:1 --timeout 0.1 status", out), 4) << out;
  EXPECT_NE(out.find("cannot connect: Connection refused"), std::string::npos) << out;
  // NaN passed CLI11's range and was named by its internal key (a technician's review).
  for (const char* bad : {"nan", "inf"}) {
    EXPECT_EQ(rig(std::string("--modbus 127.0.0.1:1 --timeout ") + bad + " status", out), 2) << out;
    EXPECT_NE(out.find(std::string("--timeout: '") + bad + "': must be a number of seconds in [0.01, 10]"), std::string::npos)
        << out;
    EXPECT_EQ(out.find("response_timeout_s"), std::string::npos) << out;
  }
  // A host that does not answer (TEST-NET-1, RFC 5737: never routed) is said so, not as the
  // non-blocking connect's "Operation now in progress" (a review); where the host's network
  // refuses at once ("Network is unreachable"), that is said.
  EXPECT_EQ(rig("--modbus 192.0.2.10:502 --timeout 0.2 status", out), 4) << out;
  EXPECT_TRUE(out.find("cannot connect: no answer within 0.2 s (host unreachable") != std::string::npos ||
              out.find("cannot connect: Network is unreachable") != std::string::npos)
      << out;
}

// A [table] setting beyond what the drive accepts is named by its key and the line that wrote it
// (the drive's maximum is only the drive's to know: exit 4 at the first command).
TEST_F(RigTable, ASettingTheDriveRefusesIsNamedByItsKey) {
  const std::string hw = testing::TempDir() + "/too-fast.toml";
  {
    FILE* f = std::fopen(hw.c_str(), "w");
    std::fprintf(f, "[table]\nmodbus = \"%s\"\nvelocity_dps = 3999.0\n", server_.endpoint().c_str());
    std::fclose(f);
  }
  std::string out;
  EXPECT_EQ(rig("--hardware " + hw + " home", out), 4) << out;
  EXPECT_NE(out.find(hw + ":3:16: [table] velocity_dps = 3999: the drive refused the value: write 2 registers at 10"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("exception 0x03 illegal data value"), std::string::npos) << out;
}

TEST_F(RigTable, UsageErrorsExitWithTwo) {
  std::string out;
  EXPECT_EQ(rig("status", out), 2) << out;
  EXPECT_NE(out.find("say where the table is"), std::string::npos) << out;
  EXPECT_EQ(rig("--modbus nowhere status", out), 2) << out;
  // Each option named as typed, not as "command-line option" or its internal key (a review).
  for (const auto& [args, says] : std::vector<std::pair<std::string, std::string>>{
           {"--modbus localhost:99999 status", "--modbus: Modbus TCP address 'localhost:99999': port out of range"},
           {"--modbus localhost:0 status", "--modbus: Modbus TCP address 'localhost:0': port 0 is no drive's port"},
           {"--modbus localhost status", "--modbus: Modbus TCP address 'localhost' must be HOST:PORT"},
           {"--rtu /dev/ttyUSB0,9600,X,8,1 status", "--rtu: Modbus RTU port '/dev/ttyUSB0,9600,X,8,1': parity must be N, E or O"},
           {"--modbus localhost:502 --drive-map " + std::string(RIG_SOURCE_DIR) + "/drives/generic-cia402.toml status",
            "rig table: --drive-map is for --drive cia402 (the drive is rig-v1 unless"},
           {"--modbus localhost:502 --drive cia402 status", "rig table: --drive cia402 needs --drive-map FILE"}}) {
    EXPECT_EQ(rig(args, out), 2) << args << ": " << out;
    EXPECT_NE(out.find(says), std::string::npos) << args << ": " << out;
    EXPECT_EQ(out.find("command-line option"), std::string::npos) << args << ": " << out;
  }
  EXPECT_EQ(rig(where_ + " move", out), 2) << out;
  EXPECT_EQ(rig(where_ + " --rtu /dev/null status", out), 2) << out;  // --modbus and --rtu exclude each other
  // An angle that is not a decimal number never moves the table: an empty shell variable read
  // as 0 degrees, and "0x10" as 16 (a review). The table stays where it is.
  ASSERT_EQ(rig(where_ + " home", out), 0) << out;
  ASSERT_EQ(rig(where_ + " move 45", out), 0) << out;
  for (const std::string bad : {"''", "0x10", "' 5'", "5deg", "1e", "--"}) {
    EXPECT_EQ(rig(where_ + " move " + bad, out), 2) << bad << ": " << out;
    if (bad != "--") {
      EXPECT_NE(out.find("is not a decimal number"), std::string::npos) << out;
    }
  }
  // A number with a unit typed after it is told to give the number alone; a malformed number is not.
  for (const auto& [bad, hint] : std::vector<std::pair<std::string, std::string>>{
           // The degree sign as typed (valid UTF-8 is not escaped: a technician's re-test read '90\xC2\xB0').
           {"90\u00B0", "'90\u00B0' is not a decimal number; give the number alone, without the degree sign: 90"},
           {"5deg", "'5deg' is not a decimal number; give the number alone, without its unit: 5"},
           {"1e", "'1e' is not a decimal number\n"},
           // Another unit, a prefix or a letter typed for a digit: no number offered (it would be
           // off by a factor, or wrong: a re-test).
           {"1.5rad", "'1.5rad' is not a decimal number\n"},
           {"9O", "'9O' is not a decimal number\n"},
           {"12.5.3", "'12.5.3' is not a decimal number\n"}}) {
    EXPECT_EQ(rig(where_ + " move '" + bad + "'", out), 2) << bad << ": " << out;
    EXPECT_NE(out.find(hint), std::string::npos) << out;
  }
  EXPECT_EQ(rig(where_ + " status", out), 0) << out;
  EXPECT_NE(out.find("45.0000"), std::string::npos) << out;
  EXPECT_EQ(rig(where_ + " --timeout 0x1 status", out), 2) << out;
  // Whole numbers: CLI11 reads "010" as octal 8 (another drive on a shared RTU bus) and "-1" as
  // 2^64 - 1 for an unsigned option (a code review).
  EXPECT_EQ(rig(where_ + " --unit 010 status", out), 2) << out;
  EXPECT_NE(out.find("'010' is not a decimal whole number (no sign, no leading zero)"), std::string::npos) << out;
  // Decimal 10: the emulator (unit 1) answers unit 10 as a gateway with no device there would.
  EXPECT_EQ(rig(where_ + " --unit 10 status", out), 4) << out;
  EXPECT_NE(out.find(" unit 10: exception 0x0B gateway target failed to respond"), std::string::npos) << out;
  // No device answers there: a stop is not written to it, as to any device not recognised as the
  // drive (a review: CONTROL 0x0100 went out after the 0x0B).
  EXPECT_EQ(rig(where_ + " --unit 10 stop", out), 4) << out;
  EXPECT_NE(out.find("stop not sent (the table may still be moving): "), std::string::npos) << out;
  EXPECT_EQ(out.find("written with SERVO_ON cleared"), std::string::npos) << out;
  EXPECT_EQ(run(std::string(RIG_BIN) + " analyze /dev/null --segment -1", out), 2) << out;
  EXPECT_NE(out.find("'-1' is not a decimal whole number (no sign, no leading zero)"), std::string::npos) << out;
  // A refused value is shown with its control bytes as \xNN, never sent to the terminal.
  EXPECT_EQ(rig(where_ + " move \"$(printf '1\\033[2J')\"", out), 2) << out;
  EXPECT_NE(out.find("'1\\x1B[2J' is not a decimal number"), std::string::npos) << out;
  EXPECT_EQ(out.find('\x1B'), std::string::npos) << out;
}

// An angle that is not finite is refused before the drive is asked: `move nan` was exit 4
// ("cannot connect") with the drive unreachable and 2 with it reachable, and `move 1e400` was
// named "inf°" (a review). Exit 2 either way, the value as typed, the table where it was.
TEST_F(RigTable, AnAngleThatIsNotFiniteIsRefusedBeforeTheDriveIsAsked) {
  std::string out;
  ASSERT_EQ(rig(where_ + " home", out), 0) << out;
  ASSERT_EQ(rig(where_ + " move 30", out), 0) << out;
  for (const std::string& where : {std::string("--modbus 127.0.0.1:1 --timeout 0.1"), where_}) {
    for (const std::string bad : {"nan", "inf"}) {
      EXPECT_EQ(rig(where + " move " + bad, out), 2) << where << " " << bad << ": " << out;
      EXPECT_NE(out.find("DEG: '" + bad + "': must be a number of degrees in [-200000, 200000]"), std::string::npos)
          << out;
      EXPECT_EQ(out.find("cannot connect"), std::string::npos) << out;
    }
    // A number no double holds says which way (1e-400 read "must be a finite number", a review).
    EXPECT_EQ(rig(where + " move 1e400", out), 2) << out;
    EXPECT_NE(out.find("DEG: '1e400' is beyond the range of a double: must be a number of degrees in [-200000, 200000]"),
              std::string::npos) << out;
    // Beyond any table's travel (the client's bound): refused as typed before the drive is asked
    // too (it was connected to first, the angle then shown as 10000000000.0000°: a review).
    EXPECT_EQ(rig(where + " move 1e10", out), 2) << out;
    EXPECT_NE(out.find("DEG: '1e10': must be a number of degrees in [-200000, 200000]"), std::string::npos) << out;
    EXPECT_EQ(out.find("cannot connect"), std::string::npos) << out;
    EXPECT_EQ(rig(where + " move 1e-400", out), 2) << out;
    EXPECT_NE(out.find("DEG: '1e-400' is nearer 0 than the smallest double: must be a number of degrees in [-200000, "
                       "200000]"),
              std::string::npos) << out;
  }
  EXPECT_NEAR(emu_->actual_angle_deg(), 30.0, 0.005);
}

// Every signal that ends the process halts a move first: Ctrl-C, a service
// manager's SIGTERM, the SIGHUP of a closed terminal or dropped ssh session, and Ctrl-\.
class RigTableSignal : public RigTable, public ::testing::WithParamInterface<int> {};

TEST_P(RigTableSignal, DuringAMoveHaltsTheTableAndExitsThree) {
  int fd = -1;
  std::unique_ptr<Child> child;
  // stderr with stdout (sh execs rig: the signal reaches rig itself).
  ASSERT_NO_FATAL_FAILURE(start_slow_move({"/bin/sh", "-c", "exec \"$0\" \"$@\" 2>&1"}, child, fd));
  ::kill(child->pid(), GetParam());
  const int st = child->wait_status();
  std::string said;
  char buf[4096];
  for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) said.append(buf, static_cast<std::size_t>(n));
  close(fd);
  ASSERT_TRUE(WIFEXITED(st)) << "killed by signal " << (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
  EXPECT_EQ(WEXITSTATUS(st), 3);
  for (int i = 0; i < 500 && emu_->snapshot().moving; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_FALSE(emu_->snapshot().moving);
  EXPECT_LT(emu_->snapshot().position_deg, 100.0);
  // Where the table came to rest, said before the abort (a technician's review: only "aborted").
  const std::string lead = "rig: the table stopped at ";
  const std::size_t at = said.find(lead);
  ASSERT_NE(at, std::string::npos) << said;
  EXPECT_NEAR(std::stod(said.substr(at + lead.size())), emu_->snapshot().position_deg, 0.01) << said;
  EXPECT_NE(said.find("° (halt delivered to the drive); it is still homed\nrig: aborted: "), std::string::npos) << said;
  // The drive's target still holds the aborted move's 300° while it reads in position at its stop
  // point: the status says the table is not there (it showed "target 300.0000°" and
  // "in-position" alone, which read as arrived).
  std::string out;
  ASSERT_EQ(rig(where_ + " status", out), 0) << out;
  const std::string note = "target     300.0000° (the table is at rest ";
  const std::size_t n = out.find(note);
  ASSERT_NE(n, std::string::npos) << out;
  EXPECT_NEAR(std::stod(out.substr(n + note.size())), 300.0 - emu_->snapshot().position_deg, 0.001) << out;
  EXPECT_NE(out.find("° from it)\n", n), std::string::npos) << out;
  ASSERT_EQ(rig(where_ + " status --json", out), 0) << out;
  EXPECT_NE(out.find("\"at_target\": false"), std::string::npos) << out;
}

// Ctrl-C with the link gone dead: the halt could not be delivered and the position not read, and
// the message says both (it said "could not be read after the halt", which read as delivered).
TEST_F(RigTable, ASignalOnADeadLinkSaysTheHaltWasNotDelivered) {
  int fd = -1;
  std::unique_ptr<Child> child;
  ASSERT_NO_FATAL_FAILURE(start_slow_move({"/bin/sh", "-c", "exec \"$0\" \"$@\" 2>&1"}, child, fd));
  emu_->inject(plant::SimFault::kNoAnswer, 0.0);
  ::kill(child->pid(), SIGINT);
  const int st = child->wait_status();
  std::string said;
  char buf[4096];
  for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) said.append(buf, static_cast<std::size_t>(n));
  close(fd);
  ASSERT_TRUE(WIFEXITED(st));
  EXPECT_EQ(WEXITSTATUS(st), 3) << said;
  EXPECT_NE(said.find("rig: the table's position could not be read after the signal ("), std::string::npos) << said;
  EXPECT_NE(said.find("); stop not confirmed (unanswered in time: the drive may still take it when it answers again; the table may still be moving): "), std::string::npos) << said;
  EXPECT_EQ(said.find("halt delivered"), std::string::npos) << said;
}

// One process at a time commands the table from this station (app/table_lock.hpp): while a move
// runs, another terminal's move, home or reset, and a hardware run on the same drive, are refused
// (exit 2) naming the holder, before anything is sent; a status and a stop still reach the drive.
TEST_F(RigTable, AMoveRunningHoldsTheTableAgainstASecondCommand) {
  int fd = -1;
  std::unique_ptr<Child> child;
  ASSERT_NO_FATAL_FAILURE(start_slow_move({"/bin/sh", "-c", "exec \"$0\" \"$@\" 2>&1"}, child, fd));
  const std::string holder = "in use by pid " + std::to_string(child->pid()) + ": rig table move 300";
  std::string out;
  for (const char* cmd : {" move 10", " home", " reset"}) {
    EXPECT_EQ(rig(where_ + cmd, out), 2) << cmd << ": " << out;
    EXPECT_NE(out.find(holder), std::string::npos) << out;
    EXPECT_NE(out.find("`rig table stop` and `rig table quick-stop` still reach the drive"), std::string::npos) << out;
  }
  // The same drive by another name of its host (a review: "localhost" took a second lock).
  const std::string port = server_.endpoint().substr(server_.endpoint().rfind(':') + 1);
  EXPECT_EQ(rig("--modbus localhost:" + port + " move 10", out), 2) << out;
  EXPECT_NE(out.find("table " + server_.endpoint() + " unit 1: " + holder), std::string::npos) << out;
  EXPECT_TRUE(emu_->snapshot().moving) << "the refused commands sent nothing";
  // A hardware run on this drive: refused before any device opens and before its folder is made.
  const std::string d = testing::TempDir() + "/table-lock-run";
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  {
    std::ofstream hw(d + "/hw.toml");
    hw << "[table]\nmodbus = \"" << server_.endpoint() << "\"\n[dut]\ncan = \"vcan-none\"\n"
       << "[gpio]\nchip = \"/dev/rig-no-such-gpiochip\"\npower = \"DUT_POWER\"\nestop = \"ESTOP\"\n"
       << "lamp_ready = \"LR\"\nlamp_running = \"LN\"\nlamp_pass = \"LP\"\nlamp_fail = \"LF\"\n";
  }
  EXPECT_EQ(run(std::string(RIG_BIN) + " run --hardware " + d + "/hw.toml --profile ci --yes --serial HW-1 --no-history --out " +
                    d + "/run",
                out),
            2)
      << out;
  EXPECT_NE(out.find("rig: in use: table " + server_.endpoint() + " unit 1: " + holder), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(d + "/run"));
  // Its dry run says so too (a re-test: it printed the plan).
  EXPECT_EQ(run(std::string(RIG_BIN) + " run --hardware " + d + "/hw.toml --profile ci --serial HW-1 --dry-run", out), 2)
      << out;
  EXPECT_NE(out.find("rig: in use: table " + server_.endpoint() + " unit 1: " + holder), std::string::npos) << out;
  ASSERT_EQ(rig(where_ + " status", out), 0) << out;
  // `rig table stop` from this station's other terminal: the operator's abort (exit 3) naming the
  // stop and where the table came to rest, not "halted by another master" (exit 4: a review).
  ASSERT_EQ(rig(where_ + " stop", out), 0) << out;
  const int st = child->wait_status();
  std::string said;
  char buf[4096];
  for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) said.append(buf, static_cast<std::size_t>(n));
  close(fd);
  ASSERT_TRUE(WIFEXITED(st));
  EXPECT_EQ(WEXITSTATUS(st), 3) << said;
  const std::string lead = "rig: the table stopped at ";
  const std::size_t at = said.find(lead);
  ASSERT_NE(at, std::string::npos) << said;
  EXPECT_NEAR(std::stod(said.substr(at + lead.size())), emu_->snapshot().position_deg, 0.01) << said;
  EXPECT_NE(said.find("° (halted by `rig table stop` (pid "), std::string::npos) << said;
  EXPECT_NE(said.find(") on this station); it is still homed\nrig: aborted: moving to 300.0000° halted by `rig table stop` (pid "),
            std::string::npos)
      << said;
  EXPECT_EQ(said.find("another master"), std::string::npos) << said;
  // Released with the process: the next command takes the table.
  ASSERT_EQ(rig(where_ + " move 10", out), 0) << out;
}

// The lock folder is shared: a symlink planted at the lock file's name is not followed (root
// would have truncated its target) and a FIFO does not hang the command; both are exit 2 naming
// the file, the drive untouched.
TEST_F(RigTable, APlantedLockFileIsNotFollowed) {
  const std::string dir = testing::TempDir() + "/planted-locks";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::string lock = server_.endpoint() + " unit 1";
  for (char& c : lock)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.') c = '_';
  lock = dir + "/rig-table-" + lock + ".lock";
  const std::string target = dir + "/precious";
  { std::ofstream(target) << "keep me\n"; }
  std::filesystem::create_symlink(target, lock);
  std::string out;
  EXPECT_EQ(run("RIG_LOCK_DIR=" + dir + " " + std::string(RIG_BIN) + " table home " + where_, out), 2) << out;
  EXPECT_NE(out.find("the lock file " + lock + " is a symbolic link, which rig does not use"), std::string::npos) << out;
  std::ifstream in(target);
  std::string kept;
  std::getline(in, kept);
  EXPECT_EQ(kept, "keep me");
  std::filesystem::remove(lock);
  ASSERT_EQ(::mkfifo(lock.c_str(), 0600), 0);
  EXPECT_EQ(run("RIG_LOCK_DIR=" + dir + " timeout 20 " + std::string(RIG_BIN) + " table home " + where_, out), 2) << out;
  EXPECT_NE(out.find("the lock file " + lock + " is not a regular file"), std::string::npos) << out;
  // A hard link to another file (its contents would be truncated by the holder's line, a re-test).
  std::filesystem::remove(lock);
  std::filesystem::create_hard_link(target, lock);
  EXPECT_EQ(run("RIG_LOCK_DIR=" + dir + " " + std::string(RIG_BIN) + " table home " + where_, out), 2) << out;
  EXPECT_NE(out.find("the lock file " + lock + " is a hard link to another file"), std::string::npos) << out;
  std::ifstream again(target);
  std::getline(again, kept);
  EXPECT_EQ(kept, "keep me");
  EXPECT_FALSE(emu_->snapshot().homed) << "nothing was sent";
  // No lock folder: the command goes on unlocked, and says so (a re-test: it was silent).
  EXPECT_EQ(run("RIG_LOCK_DIR=" + dir + "/missing " + std::string(RIG_BIN) + " table home " + where_, out), 0) << out;
  EXPECT_NE(out.find("rig: warning: the table is not locked against a second rig process on this station: cannot "
                     "open the lock file " + dir + "/missing/"),
            std::string::npos)
      << out;
}

// `nohup rig table move ...` asks that a closed terminal not end the move: SIGHUP, ignored when
// the process starts, stays ignored (a review: the watcher used to take it and halt the table).
TEST_F(RigTable, NohupKeepsAMoveGoingThroughSighup) {
  int fd = -1;
  std::unique_ptr<Child> child;
  ASSERT_NO_FATAL_FAILURE(start_slow_move({"/usr/bin/nohup"}, child, fd));
  ::kill(child->pid(), SIGHUP);
  const int st = child->wait_status();
  close(fd);
  ASSERT_TRUE(WIFEXITED(st));
  EXPECT_EQ(WEXITSTATUS(st), 0);
  EXPECT_NEAR(emu_->actual_angle_deg(), 300.0, 0.005);
}

// SIGQUIT (Ctrl-\) too: its default action ended rig with no halt, the table driving on to its
// target (a technician's re-test).
INSTANTIATE_TEST_SUITE_P(EndingSignals, RigTableSignal, ::testing::Values(SIGINT, SIGTERM, SIGHUP, SIGQUIT),
                         [](const auto& p) { return std::string(sigabbrev_np(p.param)); });

// A drive that takes the connection and never answers (a hung gateway): a CiA 402 `rig table stop`
// sends its stop's own request only, the statusword read with its one reconnect (a status read
// before it added two more timeouts, a review); a rig-v1 one still reads the status block with the
// link's retries first, to keep SERVO_ON in the HALT word (a code review; a lossy link's lost
// answers are what the retries are for), then stops. With nothing listening, the stop is said not
// delivered.
TEST(RigTableSilentLink, ACia402StopAsksOnlyForWhatItNeeds) {
  const int ls = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(ls, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(ls, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(::listen(ls, 16), 0);
  socklen_t len = sizeof a;
  ASSERT_EQ(::getsockname(ls, reinterpret_cast<sockaddr*>(&a), &len), 0);
  std::atomic<int> requests{0};
  std::atomic<bool> done{false};
  std::thread silent([&] {  // counts Modbus TCP requests (MBAP length field), answers none
    std::vector<int> conns;
    std::vector<std::string> buf;
    while (!done) {
      std::vector<pollfd> fds{{ls, POLLIN, 0}};
      for (int c : conns) fds.push_back({c, POLLIN, 0});
      if (::poll(fds.data(), fds.size(), 20) <= 0) continue;
      if (fds[0].revents & POLLIN) {
        conns.push_back(::accept4(ls, nullptr, nullptr, SOCK_CLOEXEC));
        buf.emplace_back();
      }
      for (std::size_t i = 1; i < fds.size(); ++i) {
        if (!(fds[i].revents & (POLLIN | POLLHUP))) continue;
        char b[512];
        const ssize_t n = ::read(conns[i - 1], b, sizeof b);
        if (n <= 0) continue;
        std::string& s = buf[i - 1];
        s.append(b, static_cast<std::size_t>(n));
        while (s.size() >= 6) {
          const std::size_t frame = 6u + ((static_cast<unsigned char>(s[4]) << 8) | static_cast<unsigned char>(s[5]));
          if (s.size() < frame) break;
          ++requests;
          s.erase(0, frame);
        }
      }
    }
    for (int c : conns) ::close(c);
  });
  std::string out;
  const std::string where = " --modbus 127.0.0.1:" + std::to_string(ntohs(a.sin_port)) + " --timeout 0.05 ";
  EXPECT_EQ(run(std::string(RIG_BIN) + " table" + where + "stop", out), 4) << out;
  EXPECT_NE(out.find("stop not confirmed (unanswered in time: the drive may still take it when it answers again; the table may still be moving)"), std::string::npos) << out;
  // Its servo bit was a guess (the status unread): said, since a drive that took it late (a slow
  // link, not this silent one) switched its servo off (a review).
  EXPECT_NE(out.find("; if it reached the drive: stop written with SERVO_ON cleared (CONTROL 0x0100): the drive's "
                     "state could not be read before it, so a drive that takes it also switches its servo off"),
            std::string::npos) << out;
  const int v1 = requests.exchange(0);
  EXPECT_EQ(run(std::string(RIG_BIN) + " table" + where + "--drive cia402 --drive-map " + RIG_SOURCE_DIR +
                    "/drives/generic-cia402.toml stop",
                out),
            4)
      << out;
  EXPECT_NE(out.find("halt not sent: the controlword is unknown (the statusword could not be read: "), std::string::npos)
      << out;
  EXPECT_NE(out.find("`rig table quick-stop` sends the quick stop command"), std::string::npos) << out;
  const int c4 = requests.load();
  done = true;
  silent.join();
  ::close(ls);
  for (const char* which : {"stop", "quick-stop"}) {  // the port closed: nothing listens
    EXPECT_EQ(run(std::string(RIG_BIN) + " table" + where + which, out), 4) << out;
    EXPECT_NE(out.find(std::string(which == std::string("stop") ? "stop" : "quick stop") +
                       " not delivered (the table may still be moving): modbus tcp:127.0.0.1:"),
              std::string::npos)
        << out;
    EXPECT_NE(out.find("cannot connect"), std::string::npos) << out;
  }
  EXPECT_GE(v1, 2) << "rig-v1: the status read, the stop's read and the CONTROL write";
  EXPECT_LE(c4, 2) << "CiA 402: the statusword read with one reconnect, then nothing to send";
  EXPECT_GE(c4, 1);
}

}  // namespace
}  // namespace rig::table_test

namespace rig::table_test {
namespace {

// People type the options after the action too (issue 14).
TEST_F(RigTable, OptionsMayFollowTheAction) {
  std::string out;
  ASSERT_EQ(rig("status " + where_, out), 0) << out;
  ASSERT_EQ(rig("home " + where_ + " --timeout 0.5", out), 0) << out;
  ASSERT_EQ(rig("move 45 " + where_, out), 0) << out;
  EXPECT_NEAR(emu_->actual_angle_deg(), 45.0, 0.005);
  ASSERT_EQ(rig("status --json " + where_, out), 0) << out;
  EXPECT_NE(out.find("\"homed\": true"), std::string::npos) << out;
}

// `rig plant serve --drive cia402 --drive-map MAP --profile PROFILE` as its own process; the
// " --modbus EP --drive cia402 --drive-map MAP" a `rig table` against it takes, and its endpoint.
struct ServedCia402 {
  ServedCia402(const std::string& map, const std::string& profile)
      : serve({RIG_BIN, "plant", "serve", "--modbus", "127.0.0.1:0", "--drive", "cia402", "--drive-map", map,
               "--profile", profile},
              &fd) {
    const std::string line = read_line(fd);
    EXPECT_NE(line.find("drive cia402"), std::string::npos) << line;
    ep = line.substr(line.find("tcp:") + 4, line.find(" unit") - line.find("tcp:") - 4);
    where = " --modbus " + ep + " --drive cia402 --drive-map " + map;
  }
  ~ServedCia402() { close(fd); }
  ServedCia402(const ServedCia402&) = delete;
  ServedCia402& operator=(const ServedCia402&) = delete;
  int fd = -1;
  Child serve;
  std::string ep, where;
};

// `rig plant serve --drive cia402` as its own process, `rig table --drive cia402` against it.
class RigTableCia402 : public ::testing::TestWithParam<std::string> {};

TEST_P(RigTableCia402, ServeStatusHomeMoveStopResetAndCtrlC) {
  const std::string map = std::string(RIG_SOURCE_DIR) + "/drives/" + GetParam();
  const std::string prof = testing::TempDir() + "/fast-plant.toml";
  {
    FILE* f = std::fopen(prof.c_str(), "w");
    std::fprintf(f, "base = \"ci\"\n[plant.table]\nvelocity_dps = 360.0\naccel_dps2 = 1800.0\n"
                    "home_velocity_dps = 200.0\nsettle_s = 0.05\nstart_angle_deg = 10.0\n");
    std::fclose(f);
  }
  ServedCia402 served(map, prof);
  ASSERT_FALSE(served.ep.empty());
  Child& serve = served.serve;
  const std::string& ep = served.ep;
  const std::string& where = served.where;
  std::string out;
  auto rig = [&](const std::string& args) { return run(std::string(RIG_BIN) + " table " + args, out); };
  const bool has_bit = GetParam() == "lowword-offset.toml";
  ASSERT_EQ(rig("status" + where), 0) << out;
  EXPECT_NE(out.find("cia402"), std::string::npos) << out;
  // Not homed yet: said where the map can tell (a review: "ready" alone read as ready to move).
  EXPECT_EQ(out.find("NOT-HOMED") != std::string::npos, has_bit) << out;
  // Its power stage is off (Switch on disabled): nothing to halt, none sent, exit 0, said so.
  ASSERT_EQ(rig("stop" + where), 0) << out;
  EXPECT_NE(out.find("no halt needed: drive \""), std::string::npos) << out;
  EXPECT_NE(out.find("its power stage is off"), std::string::npos) << out;
  // The default (rig-v1) client at a CiA 402 drive: refused, with what to give (a technician's
  // review: "exception 0x02 illegal data address" alone).
  EXPECT_EQ(rig("status --modbus " + ep), 4) << out;
  EXPECT_NE(out.find("exception 0x02 illegal data address (the drive has no rig-v1 status registers at 0..24: for a "
                     "CiA 402 drive give --drive cia402 --drive-map FILE"),
            std::string::npos)
      << out;
  EXPECT_EQ(out.find(ep), out.rfind(ep)) << "the device named once: " << out;
  // Nor does it send a stop bit into the CiA 402 drive (HALT alone is Disable voltage there).
  for (const char* stop : {"stop", "quick-stop"}) {
    EXPECT_EQ(rig(std::string(stop) + " --modbus " + ep), 4) << out;
    EXPECT_NE(out.find("stop not sent (the table may still be moving): "), std::string::npos) << out;
    EXPECT_NE(out.find("no rig-v1 status registers at 0..24"), std::string::npos) << out;
  }
  ASSERT_EQ(rig("home" + where), 0) << out;
  ASSERT_EQ(rig("move 180" + where), 0) << out;
  EXPECT_NE(out.find("actual     180.0000°"), std::string::npos) << out;
  EXPECT_NE(out.find("in-position"), std::string::npos) << out;
  // Homing is another process's: a map with homed_bit reads it from the drive; one without
  // cannot tell, and says so (helper review: it said "homed": false, as if the reference was lost).
  ASSERT_EQ(rig("status --json" + where), 0) << out;
  EXPECT_NE(out.find(has_bit ? "\"homed\": true" : "\"homed\": false"), std::string::npos) << out;
  EXPECT_EQ(out.find("\"homed_known\": false") != std::string::npos, !has_bit) << out;
  ASSERT_EQ(rig("status" + where), 0) << out;
  EXPECT_EQ(out.find("homed-unknown") != std::string::npos, !has_bit) << out;
  EXPECT_EQ(out.find("NOT-HOMED"), std::string::npos) << out;
  ASSERT_EQ(rig("stop" + where), 0) << out;
  EXPECT_NE(out.find("stop sent"), std::string::npos) << out;
  ASSERT_EQ(rig("quick-stop" + where), 0) << out;
  ASSERT_EQ(rig("status" + where), 0) << out;  // the drive's own state, which the flags cannot show
  EXPECT_NE(out.find("drive      Quick stop active (CiA 402)"), std::string::npos) << out;
  EXPECT_EQ(out.find("heartbeat"), std::string::npos) << "a CiA 402 drive has no heartbeat register: " << out;
  ASSERT_EQ(rig("move 0" + where), 0) << out;  // back up from Quick stop active
  ASSERT_EQ(rig("reset" + where), 0) << out;   // no fault: nothing to clear
  EXPECT_EQ(rig("move 1000" + where), 2) << out;  // outside the map's travel limits
  EXPECT_NE(out.find("outside the travel limits"), std::string::npos) << out;
  EXPECT_NE(out.find("; nothing sent"), std::string::npos) << out;
  // Ctrl-C mid-move: halted, exit 3.
  int cfd = -1;
  Child child({"/bin/sh", "-c", "exec \"$0\" \"$@\" 2>&1", RIG_BIN, "table", "move", "300", "--modbus", ep, "--drive",
               "cia402", "--drive-map", map},
              &cfd);
  // Once the table turns (the drive has taken 300° as its target): a fixed wait let a loaded
  // machine's signal come first, with the target still 0° and the table at it (a code review).
  std::string turning;
  for (int i = 0; i < 200 && !has(turning, "\"moving\": true"); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    rig("status --json" + where);
    turning = out;
  }
  ASSERT_TRUE(has(turning, "\"moving\": true")) << turning;
  ::kill(child.pid(), SIGINT);
  const int st = child.wait_status();
  std::string said;
  char buf[4096];
  for (ssize_t n; (n = ::read(cfd, buf, sizeof buf)) > 0;) said.append(buf, static_cast<std::size_t>(n));
  close(cfd);
  ASSERT_TRUE(WIFEXITED(st));
  EXPECT_EQ(WEXITSTATUS(st), 3);
  // Whether it is still homed, said either way (a map without homed_bit said nothing: a review).
  EXPECT_NE(said.find(has_bit ? "(halt delivered to the drive); it is still homed\n"
                              : "(halt delivered to the drive); whether it is still homed the drive cannot say (its map "
                                "has no homed_bit)"),
            std::string::npos)
      << said;
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  ASSERT_EQ(rig("status --json" + where), 0) << out;
  EXPECT_NE(out.find("\"moving\": false"), std::string::npos) << out;
  const auto p = out.find("\"actual_deg\": ");
  ASSERT_NE(p, std::string::npos) << out;
  EXPECT_LT(std::stod(out.substr(p + 14)), 290.0) << out;
  EXPECT_NE(out.find("\"at_target\": false"), std::string::npos) << "the aborted 300° is not where it is: " << out;
  // The server gone: exit 4 naming the drive.
  serve.kill_now();
  EXPECT_EQ(rig("move 10 --timeout 0.1" + where), 4) << out;
}

INSTANTIATE_TEST_SUITE_P(ShippedMaps, RigTableCia402, ::testing::Values("generic-cia402.toml", "lowword-offset.toml"),
                         [](const auto& p) { return p.param.substr(0, p.param.find('-')); });

TEST(RigTableHardwareFile, DriveAndMapErrorsNameTheFile) {
  const std::string dir = testing::TempDir();
  auto write = [&](const std::string& name, const std::string& text) {
    FILE* f = std::fopen((dir + "/" + name).c_str(), "w");
    std::fputs(text.c_str(), f);
    std::fclose(f);
    return dir + "/" + name;
  };
  std::string out;
  const std::string hw1 = write("hw1.toml", "[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive = \"canopen\"\n");
  EXPECT_EQ(run(std::string(RIG_BIN) + " table status --hardware " + hw1, out), 2) << out;
  EXPECT_NE(out.find("hw1.toml:3:"), std::string::npos) << out;
  const std::string hw2 = write("hw2.toml", "[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive = \"cia402\"\ndrive_map = \"nomap.toml\"\n");
  EXPECT_EQ(run(std::string(RIG_BIN) + " table status --hardware " + hw2, out), 2) << out;
  EXPECT_NE(out.find("hw2.toml:4:"), std::string::npos) << out;
  EXPECT_NE(out.find("not found"), std::string::npos) << out;
  // An empty drive_map is named as empty (it read "drive map '' not found: looked beside ..."),
  // and a file's map left out with --drive rig-v1 is said, not dropped silently (a review).
  const std::string hw2e = write("hw2e.toml", "[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive = \"cia402\"\ndrive_map = \"\"\n");
  EXPECT_EQ(run(std::string(RIG_BIN) + " table status --hardware " + hw2e, out), 2) << out;
  EXPECT_NE(out.find("hw2e.toml:4:13: drive_map is empty: name a drive map file"), std::string::npos) << out;
  const std::string hw2v = write("hw2v.toml", "[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive = \"cia402\"\n"
                                              "drive_map = \"" + std::string(RIG_SOURCE_DIR) + "/drives/generic-cia402.toml\"\n");
  EXPECT_EQ(run(std::string(RIG_BIN) + " table --timeout 0.05 status --hardware " + hw2v + " --drive rig-v1", out), 4) << out;
  EXPECT_NE(out.find("hw2v.toml:4:13: drive_map is for a CiA 402 drive: not used with --drive rig-v1"), std::string::npos)
      << out;
  // A map beside the hardware file, with an error in it: the map's file and line.
  write("badmap.toml", "[drive]\nname = \"x\"\nbogus = 1\n");
  const std::string hw3 = write("hw3.toml", "[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive = \"cia402\"\ndrive_map = \"badmap.toml\"\n");
  EXPECT_EQ(run(std::string(RIG_BIN) + " table status --hardware " + hw3, out), 2) << out;
  EXPECT_NE(out.find("badmap.toml:3:"), std::string::npos) << out;
  // `rig run --hardware`: the [table] mistake is exit 2 before any device is opened
  // (here GPIO would fail with exit 4: no such chip on this machine).
  const std::string hw4 = write("hw4.toml", "[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive = \"cia402\"\n"
                                            "drive_map = \"badmap.toml\"\n[dut]\ncan = \"vcan9\"\n"
                                            "[gpio]\nchip = \"nochip\"\npower = \"P\"\nestop = \"E\"\n");
  EXPECT_EQ(run(std::string(RIG_BIN) + " run --hardware " + hw4 + " --profile ci --yes --out " + dir + "/run4", out), 2)
      << out;
  EXPECT_NE(out.find("badmap.toml:3:"), std::string::npos) << out;
  // A [table] speed that does not fit the map's profile register is named at its line, before
  // the drive is opened (it was cut to its low 16 bits: the table crept, a review).
  write("map16.toml", "[drive]\nname = \"m16\"\n[scaling]\ncounts_per_rev = 131072\n[limits]\nneg_deg = -10.0\n"
                      "pos_deg = 10.0\n[objects]\ncontrolword = { index = 0x6040, address = 0 }\n"
                      "statusword = { index = 0x6041, address = 1 }\nerror_code = { index = 0x603F, address = 2 }\n"
                      "modes_of_operation = { index = 0x6060, address = 3, signed = true }\n"
                      "modes_of_operation_display = { index = 0x6061, address = 4, signed = true }\n"
                      "position_actual = { index = 0x6064, address = 5, width = 32, signed = true }\n"
                      "velocity_actual = { index = 0x606C, address = 7, width = 32, signed = true }\n"
                      "target_position = { index = 0x607A, address = 9, width = 32, signed = true }\n"
                      "profile_velocity = { index = 0x6081, address = 11 }\n");
  const std::string hw5 = write("hw5.toml", "[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive = \"cia402\"\n"
                                            "drive_map = \"map16.toml\"\nvelocity_dps = 200.0\n");
  EXPECT_EQ(run(std::string(RIG_BIN) + " table status --hardware " + hw5, out), 2) << out;
  EXPECT_NE(out.find("hw5.toml:5:"), std::string::npos) << out;
  EXPECT_NE(out.find("[table] velocity_dps = 200 is 72818 counts/s in the drive's units, which does not fit "
                     "profile_velocity (0x6081) at holding register 11, a 16-bit unsigned register: 0..65535"),
            std::string::npos)
      << out;
  // A speed the map has no object for would never be sent (the drive moving at its own while the
  // dry run said "as sent": an integrator's review): refused at its line too.
  const std::string hw5a = write("hw5a.toml", "[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive = \"cia402\"\n"
                                              "drive_map = \"map16.toml\"\nvelocity_dps = 2.0\naccel_dps2 = 90.0\n");
  EXPECT_EQ(run(std::string(RIG_BIN) + " table status --hardware " + hw5a, out), 2) << out;
  EXPECT_NE(out.find("hw5a.toml:6:"), std::string::npos) << out;
  EXPECT_NE(out.find("[table] accel_dps2 = 90 cannot be sent: drive map "), std::string::npos) << out;
  EXPECT_NE(out.find(" has no profile_acceleration (0x6083) or profile_deceleration (0x6084) object, so the drive would "
                     "move at the value it holds; add the object to the map or leave accel_dps2 out"),
            std::string::npos)
      << out;
  // The procedure's U20 (180 degrees) outside the map's travel (+-10): refused by the dry run,
  // before any device opens (it failed at the first U20 move, after run01 was recorded).
  const std::string hw6 = write("hw6.toml", "[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive = \"cia402\"\n"
                                            "drive_map = \"map16.toml\"\n[dut]\ncan = \"vcan9\"\n"
                                            "[gpio]\nchip = \"nochip\"\npower = \"P\"\nestop = \"E\"\n");
  for (const char* dry : {" --dry-run", ""}) {
    EXPECT_EQ(run(std::string(RIG_BIN) + " run --hardware " + hw6 + " --profile ci --yes --no-history --out " + dir +
                      "/run6" + dry,
                  out),
              2)
        << out;
    EXPECT_NE(out.find("u20_deg = 180°: outside the table's travel [-10°, 10°] (drive map"), std::string::npos) << out;
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/run6/run.json"));
}

// A drive map in motor rpm through 50:1 (the review's "Acme SD-9"), for the [table] checks below.
const char* const kRpmMap =
    "[drive]\nname = \"rpm 50:1\"\n[scaling]\ncounts_per_rev = 1048576\ngear_ratio = 50.0\nvelocity_unit = \"rpm\"\n"
    "acceleration_unit = \"rpm_per_s\"\n[limits]\nneg_deg = -10.0\npos_deg = 200.0\n[objects]\n"
    "controlword = { index = 0x6040, address = 0 }\nstatusword = { index = 0x6041, address = 1 }\n"
    "error_code = { index = 0x603F, address = 2 }\nmodes_of_operation = { index = 0x6060, address = 3, signed = true }\n"
    "modes_of_operation_display = { index = 0x6061, address = 4, signed = true }\n"
    "position_actual = { index = 0x6064, address = 5, width = 32, signed = true }\n"
    "velocity_actual = { index = 0x606C, address = 7, width = 32, signed = true }\n"
    "target_position = { index = 0x607A, address = 9, width = 32, signed = true }\n"
    "profile_velocity = { index = 0x6081, address = 11, width = 32 }\n"
    "profile_acceleration = { index = 0x6083, address = 13, width = 32 }\n"
    "profile_deceleration = { index = 0x6084, address = 15, width = 32 }\n"
    "device_type = { index = 0x1000, address = 32, width = 32 }\n";

std::string write_file(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  FILE* f = std::fopen(path.c_str(), "w");
  std::fputs(text.c_str(), f);
  std::fclose(f);
  return path;
}

// [table] values no drive can honour, refused when the file is read (exit 2 at the key's line,
// before any device opens; each was accepted, then failed or misled at the drive, a review).
TEST(RigTableHardwareFile, ValuesNoDriveCanHonourAreRefusedAtTheirLine) {
  const std::string dir = testing::TempDir() + "/honour";
  write_file(dir + "/rpm.toml", kRpmMap);
  const std::string head = "[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive = \"cia402\"\ndrive_map = \"rpm.toml\"\n";
  std::string out;
  auto status = [&](const std::string& table) {
    return run(std::string(RIG_BIN) + " table status --hardware " + write_file(dir + "/hw.toml", table), out);
  };
  // A speed or acceleration that rounds to 0 in the drive's units: sent as 0, the move timed out
  // blaming the drive ("drive frozen").
  EXPECT_EQ(status(head + "velocity_dps = 0.05\n"), 2) << out;
  EXPECT_TRUE(has(out, "hw.toml:5:16: [table] velocity_dps = 0.05 is 0.4167 rpm in the drive's units, which rounds to "
                       "0: sent as 0, the drive would not move; the least it can be sent is 1 rpm = 0.12 °/s"))
      << out;
  EXPECT_EQ(status(head + "accel_dps2 = 0.05\n"), 2) << out;
  EXPECT_TRUE(has(out, "hw.toml:5:14: [table] accel_dps2 = 0.05 is 0.4167 rpm/s in the drive's units, which rounds to 0"))
      << out;
  // Rounded by more than 1 %: said once (then the drive, absent here, is exit 4 as before).
  EXPECT_EQ(status(head + "velocity_dps = 1.0\naccel_dps2 = 24.0\n"), 4) << out;
  EXPECT_TRUE(has(out, "rig: warning: " + dir + "/hw.toml:5:16: [table] velocity_dps = 1 is 8.333 rpm in the drive's "
                       "units, sent as 8 rpm = 0.96 °/s (4.0 % less)"))
      << out;
  EXPECT_EQ(out.find("warning"), out.rfind("warning")) << "said once: " << out;
  EXPECT_FALSE(has(out, "accel_dps2")) << "200 rpm/s exactly: " << out;
  // A drive counting 0.1 rpm: its units named in the message (4.167 of them, sent as 4).
  std::string tenths = kRpmMap;
  tenths.replace(tenths.find("velocity_unit = \"rpm\"\n"), 22, "velocity_unit = \"rpm\"\nvelocity_resolution = 0.1\n");
  write_file(dir + "/rpm.toml", tenths);
  EXPECT_EQ(status(head + "velocity_dps = 0.05\n"), 4) << out;
  EXPECT_TRUE(has(out, "hw.toml:5:16: [table] velocity_dps = 0.05 is 4.167 × 0.1 rpm in the drive's units, sent as 4 "
                       "× 0.1 rpm = 0.048 °/s (4.0 % less)"))
      << out;
  write_file(dir + "/rpm.toml", kRpmMap);
  // A tolerance below one position count: no move could ever be confirmed.
  EXPECT_EQ(status(head + "tolerance_deg = 0\n"), 2) << out;
  EXPECT_TRUE(has(out, "hw.toml:5:17: 'tolerance_deg' = 0: below one position count of the drive (6.87e-06°, drive map"))
      << out;
  EXPECT_EQ(status(head + "tolerance_deg = 0.00001\n"), 4) << out;  // above one count: accepted
  EXPECT_EQ(status("[table]\nmodbus = \"tcp:127.0.0.1:1\"\ntolerance_deg = 0.00005\n"), 2) << out;
  EXPECT_TRUE(has(out, "hw.toml:3:17: 'tolerance_deg' = 5e-05: below") && has(out, "(0.0001°, rig-v1 register map)"))
      << "the value as written, not 5.0000000000000002e-05: " << out;
  // [table] u10_deg outside the map's travel (the run takes [procedure]'s, and would fail there).
  EXPECT_EQ(status(head + "u10_deg = 300.0\nu20_deg = 120.0\n"), 2) << out;
  EXPECT_TRUE(has(out, "hw.toml:5:11: 'u10_deg' = 300.0: outside the table's travel [-10°, 200°]")) << out;
  // The two holds a drive's timing may need raised: in range, and the set-point acknowledge's
  // only where there is one (CiA 402).
  EXPECT_EQ(status(head + "ended_short_s = 0\n"), 2) << out;
  EXPECT_TRUE(has(out, "hw.toml:5:17:") && has(out, "ended_short_s")) << out;
  EXPECT_EQ(status(head + "unacked_motion_s = 61\n"), 2) << out;
  EXPECT_TRUE(has(out, "hw.toml:5:20:") && has(out, "unacked_motion_s")) << out;
  EXPECT_EQ(status(head + "ended_short_s = 3.0\nunacked_motion_s = 0.5\n"), 4) << out;  // accepted; no drive here
  EXPECT_EQ(status("[table]\nmodbus = \"tcp:127.0.0.1:1\"\nunacked_motion_s = 0.5\n"), 2) << out;
  EXPECT_TRUE(has(out, "hw.toml:3:20: 'unacked_motion_s' = 0.5: is for drive = \"cia402\"") &&
              has(out, "this table is drive = \"rig-v1\" (the default)"))
      << out;
  EXPECT_EQ(status("[table]\nmodbus = \"tcp:127.0.0.1:1\"\nended_short_s = 3.0\n"), 4) << out;  // both maps
  // The protocol from the command line over the file's: the refusal names the flag, not only the
  // key's line in a file that says drive = "cia402" (it blamed the file alone).
  const std::string file = write_file(dir + "/hw.toml", head + "unacked_motion_s = 0.5\n");
  EXPECT_EQ(run(std::string(RIG_BIN) + " table status --drive rig-v1 --hardware " + file, out), 2) << out;
  EXPECT_TRUE(has(out, "hw.toml:5:20: 'unacked_motion_s' = 0.5: is for drive = \"cia402\"") &&
              has(out, "this table is drive = \"rig-v1\" (--drive rig-v1)"))
      << out;
  EXPECT_EQ(status("[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive = \"rig-v1\"\nunacked_motion_s = 0.5\n"), 2) << out;
  EXPECT_TRUE(has(out, "this table is drive = \"rig-v1\" (" + dir + "/hw.toml:3:9)")) << out;
  const std::string v1 = write_file(dir + "/v1.toml", "[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive_settle_s = 0.5\n");
  EXPECT_EQ(run(std::string(RIG_BIN) + " table status --drive cia402 --drive-map " + dir + "/rpm.toml --hardware " + v1, out),
            2)
      << out;
  EXPECT_TRUE(has(out, "v1.toml:3:18: 'drive_settle_s' = 0.5: is a rig-v1 register") &&
              has(out, "this table is drive = \"cia402\" (--drive cia402)"))
      << out;
  // A file right only with the flags (it was refused naming the file's protocol, an outside
  // review): used, with the file's own refusal said as a warning, since `rig run --hardware`
  // refuses it; the drive, absent, is exit 4.
  const std::string v1_unacked = write_file(dir + "/v1u.toml", "[table]\nmodbus = \"tcp:127.0.0.1:1\"\nunacked_motion_s = 0.25\n");
  EXPECT_EQ(run(std::string(RIG_BIN) + " table status --drive cia402 --drive-map " + dir + "/rpm.toml --hardware " + v1_unacked,
                out),
            4)
      << out;
  EXPECT_TRUE(has(out, "rig: warning: " + v1_unacked + ":3:20: 'unacked_motion_s' = 0.25: is for drive = \"cia402\"") &&
              has(out, "(taken here with the command line's options over the file; `rig run --hardware " + v1_unacked +
                           "` refuses it)"))
      << out;
  const std::string c4_window = write_file(dir + "/c4w.toml", head + "in_position_window_deg = 0.002\n");
  EXPECT_EQ(run(std::string(RIG_BIN) + " table status --drive rig-v1 --hardware " + c4_window, out), 4) << out;
  EXPECT_TRUE(has(out, "rig: warning: " + c4_window + ":5:26: 'in_position_window_deg' = 0.002")) << out;
  const std::string c4_nomap = write_file(dir + "/c4n.toml", "[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive = \"cia402\"\n");
  EXPECT_EQ(run(std::string(RIG_BIN) + " table status --drive rig-v1 --hardware " + c4_nomap, out), 4) << out;
  EXPECT_TRUE(has(out, "rig: warning: ") && has(out, "needs drive_map")) << out;
  // Checked alone too: the file's own broken map under --drive rig-v1 is still refused, and a
  // map for a protocol that has none is a usage error, as `rig plant serve` has it.
  const std::string c4_badmap = write_file(dir + "/c4b.toml", "[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive = \"cia402\"\n"
                                                               "drive_map = \"missing.toml\"\n");
  EXPECT_EQ(run(std::string(RIG_BIN) + " table status --drive rig-v1 --hardware " + c4_badmap, out), 4) << out;
  EXPECT_TRUE(has(out, "rig: warning: " + c4_badmap + ":4:13: drive map 'missing.toml' not found")) << out;
  EXPECT_EQ(run(std::string(RIG_BIN) + " table status --drive rig-v1 --drive-map " + dir + "/rpm.toml --hardware " + c4_window,
                out),
            2)
      << out;
  EXPECT_TRUE(has(out, "rig: configuration error: rig table: --drive-map is for --drive cia402")) << out;
  // A file's own rig-v1 with a drive map is still its own mistake.
  EXPECT_EQ(status("[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive = \"rig-v1\"\ndrive_map = \"rpm.toml\"\n"), 2) << out;
  EXPECT_TRUE(has(out, "hw.toml:4:13: drive_map is for drive = \"cia402\"")) << out;
}

// Link settings no drive answers on, refused with the file (exit 2 at the line), as port 70000
// and -1 are: port 0 (a server's "any port"; it was exit 4, "cannot connect") and 7 data bits
// (Modbus ASCII's; RTU is 8).
TEST(RigTableHardwareFile, LinkSettingsNoDriveAnswersOnAreRefused) {
  const std::string dir = testing::TempDir() + "/link";
  std::string out;
  auto status = [&](const std::string& table) {
    return run(std::string(RIG_BIN) + " table status --hardware " + write_file(dir + "/hw.toml", table), out);
  };
  EXPECT_EQ(status("[table]\nmodbus = \"tcp:127.0.0.1:0\"\n"), 2) << out;
  EXPECT_TRUE(has(out, "hw.toml:2:10: 'modbus' = 'tcp:127.0.0.1:0': port 0 is no drive's port (1..65535)")) << out;
  EXPECT_EQ(run(std::string(RIG_BIN) + " table --modbus 127.0.0.1:0 status", out), 2) << out;
  EXPECT_TRUE(has(out, "port 0 is no drive's port")) << out;
  EXPECT_EQ(status("[table]\nrtu = \"/dev/ttyS0,19200,N,7,2\"\n"), 2) << out;
  EXPECT_TRUE(has(out, "hw.toml:2:7: Modbus RTU port '/dev/ttyS0,19200,N,7,2': 7 data bits: Modbus RTU needs 8")) << out;
  EXPECT_EQ(run(std::string(RIG_BIN) + " table --rtu /dev/ttyS0,19200,N,7,2 status", out), 2) << out;
  // [gpio]'s unknown key is "in [gpio]" (it said "in [[gpio]]").
  EXPECT_EQ(status("[table]\nmodbus = \"tcp:127.0.0.1:1\"\n[gpio]\npower = \"P\"\nestop = \"E\"\nbogus = 1\n"), 2) << out;
  EXPECT_TRUE(has(out, "hw.toml:6:1: unknown key 'bogus' in [gpio] (expected")) << out;
}

// The drive map is looked for beside the hardware file, then in the working folder: a map not
// found names both places; one found only in the working folder is said (its travel limits then
// depend on where rig is started).
TEST(RigTableHardwareFile, TheDriveMapsPlacesAreNamed) {
  const std::string dir = (std::filesystem::path(testing::TempDir()) / "map-places").lexically_normal().string();
  const std::string hw = write_file(dir + "/site/hw.toml", "[table]\nmodbus = \"tcp:127.0.0.1:1\"\ndrive = \"cia402\"\n"
                                                           "drive_map = \"rpm.toml\"\n");
  std::filesystem::create_directories(dir + "/cwd");
  std::string out;
  const std::string cmd = "cd " + dir + "/cwd && " + RIG_BIN + " table status --hardware " + hw;
  EXPECT_EQ(run(cmd, out), 2) << out;
  EXPECT_TRUE(has(out, "hw.toml:4:13: drive map 'rpm.toml' not found: looked beside " + hw + " (" + dir +
                           "/site/rpm.toml), then in the working folder (" + dir + "/cwd/rpm.toml)"))
      << out;
  write_file(dir + "/cwd/rpm.toml", kRpmMap);
  EXPECT_EQ(run(cmd, out), 4) << out;  // found; the drive (absent) is exit 4
  EXPECT_TRUE(has(out, "rig: warning: " + hw + ":4:13: drive map 'rpm.toml' is not beside " + hw +
                           "; taken from the working folder (" + dir + "/cwd/rpm.toml)"))
      << out;
  write_file(dir + "/site/rpm.toml", kRpmMap);  // beside the file: taken first, nothing to say
  EXPECT_EQ(run(cmd, out), 4) << out;
  EXPECT_FALSE(has(out, "warning")) << out;
}

// Two masters on one CiA 402 drive, as processes: `rig table stop` from another shell ends a
// running `rig table move` at once as "halted by another master", and a second `rig table move`
// waits for the first one's motion to end instead of writing its set-point under it; the first
// then ends naming the other master and sends no halt over its move (it waited out its move
// timeout, then halted whatever the table did, a review).
TEST(RigTableCia402Masters, AnotherProcesssStopOrMoveIsNamedAndNotHaltedOver) {
  const std::string map = std::string(RIG_SOURCE_DIR) + "/drives/generic-cia402.toml";
  const std::string prof = write_file(testing::TempDir() + "/masters/plant.toml",
                                      "base = \"ci\"\n[plant.table]\nvelocity_dps = 90.0\naccel_dps2 = 900.0\n"
                                      "home_velocity_dps = 200.0\nsettle_s = 0.05\nstart_angle_deg = 10.0\n");
  ServedCia402 served(map, prof);
  ASSERT_FALSE(served.ep.empty());
  const std::string& where = served.where;
  std::string out;
  auto rig = [&](const std::string& args, std::string& o) { return run(std::string(RIG_BIN) + " table " + args + where, o); };
  ASSERT_EQ(rig("home", out), 0) << out;
  // Until the table has turned 2° from where it stood: the other process's move is under way.
  auto actual = [&] {
    if (rig("status --json", out) != 0 || !has(out, "\"actual_deg\": ")) return std::nan("");
    return std::stod(out.substr(out.find("\"actual_deg\": ") + 14));
  };
  auto wait_moving = [&] {
    const double from = actual();
    for (int i = 0; i < 300; ++i) {
      if (std::fabs(actual() - from) > 2.0) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
  };
  // `rig table stop` from another process.
  int rc1 = -1;
  std::string out1;
  std::thread first([&] { rc1 = rig("move 300", out1); });
  ASSERT_TRUE(wait_moving()) << out;
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(rig("stop", out), 0) << out;
  first.join();
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 3.0) << out1;
  EXPECT_EQ(rc1, 3) << out1;
  EXPECT_TRUE(has(out1, "rig: aborted: moving to 300.0000° halted by `rig table stop` (pid ") &&
              has(out1, ") on this station") && !has(out1, "another master")) << out1;
  // The same stop from another station (its own lock folder: no note here) is another master's
  // halt, exit 4 as the drive says it; a stop noted before a move began is not taken for it.
  for (int i = 0; i < 300 && (rig("status --json", out) != 0 || !has(out, "\"moving\": false")); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  const std::string elsewhere = testing::TempDir() + "/masters/stop-station";
  std::filesystem::create_directories(elsewhere);
  // This station's note made to say it comes from the future (a clock stepped back, a file planted
  // in a shared lock folder): no stop's, so the halt below stays another master's (a re-test).
  for (const auto& e : std::filesystem::directory_iterator(std::getenv("RIG_LOCK_DIR")))
    if (e.path().extension() == ".stop") std::ofstream(e.path()) << "9999999999999999999 pid 1: rig table stop\n";
  // The farther end of the travel from where the first halt left it: a long move, still under
  // way when the other station's stop comes on a loaded machine.
  const double rest = actual();
  const std::string far = rest > 90.0 ? "-150" : "350";
  std::thread halted_elsewhere([&] { rc1 = rig("move " + far, out1); });
  ASSERT_TRUE(wait_moving()) << out;
  EXPECT_EQ(run("RIG_LOCK_DIR=" + elsewhere + " " + std::string(RIG_BIN) + " table stop" + where, out), 0) << out;
  halted_elsewhere.join();
  EXPECT_EQ(rc1, 4) << out1;
  EXPECT_TRUE(has(out1, "move to " + far + ".0000°: halted by another master (controlword reads 0x010F)") &&
              has(out1, "; no halt sent by this client")) << out1;
  // A second `rig table move` while the first runs: it waits, then both moves are the table's.
  // The halted table first comes to rest: still coasting from the halt, it looked like the next
  // move under way, and the two moves started together (the race showed once the first process
  // exited without waiting out its watchers' polling slices).
  for (int i = 0; i < 300 && (rig("status --json", out) != 0 || !has(out, "\"moving\": false")); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_TRUE(has(out, "\"moving\": false")) << out;
  std::thread again([&] { rc1 = rig("move 250", out1); });
  ASSERT_TRUE(wait_moving()) << out;
  std::string out2;
  // From this station the second move is refused by the table lock (app/table_lock.hpp) before
  // anything is sent; from another station (its own lock folder) the drive's checks hold it.
  EXPECT_EQ(rig("move 20", out2), 2) << out2;
  EXPECT_TRUE(has(out2, ": in use by pid ") && has(out2, ": rig table move 250.0000°")) << out2;
  const std::string other_station = testing::TempDir() + "/masters/other-station";
  std::filesystem::create_directories(other_station);
  EXPECT_EQ(run("RIG_LOCK_DIR=" + other_station + " " + std::string(RIG_BIN) + " table move 20" + where, out2), 0) << out2;
  again.join();
  EXPECT_TRUE(has(out2, "actual     20.0000°")) << out2;
  // The first reached 250° before the second's set-point; ended then as arrived, or in its settle
  // time naming the other master, never a timeout nor a halt over the second's move. The second
  // begins with halt set (its handshake, cia402_client.cpp): read in the first's settle time, that
  // is "halted by another master" (CI's sanitizer pass saw it once), else its new target or mode.
  if (rc1 != 0) {
    EXPECT_TRUE(rc1 == 4 &&
                (has(out1, "(another Modbus master?)") || has(out1, ": halted by another master (controlword reads 0x010F)")) &&
                has(out1, "; no halt sent by this client")) << out1;
  }
  EXPECT_FALSE(has(out1, "timed out")) << out1;
}

}  // namespace
}  // namespace rig::table_test
