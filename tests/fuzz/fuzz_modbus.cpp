// A misbehaving drive behind the Modbus client (issue 13): the register replies, exception
// replies and timeouts come from the fuzz input through a fake RegisterTransport (the seam the
// libmodbus transport implements), and the input also picks the calls the rig makes -- status,
// home, move, stop, quick stop, alarm reset -- on the rig-v1 client or the CiA 402 client
// (drives/generic-cia402.toml). Time is simulated, so every wait is bounded by its timeout
// without sleeping. A hostile drive may only ever cause a rig error (HardwareError, exit 4);
// statuses stay finite, and a failed home or move says whether the halt reached the drive (a
// technician must know if the table may still be turning, issue 13 item 8).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rig/modbus/cia402_client.hpp"
#include "rig/modbus/drive_map.hpp"
#include "rig/modbus/table_client.hpp"
#include "tests/fuzz/fuzz_target.hpp"

namespace {

using rig::modbus::ModbusError;

// The fuzz input, read front to back; past its end every reply is a timeout (a silent drive).
struct Input {
  const uint8_t* p;
  std::size_t n;
  std::size_t i = 0;
  bool done() const { return i >= n; }
  uint8_t u8() { return i < n ? p[i++] : 0; }
  uint16_t u16() { return static_cast<uint16_t>(u8() | (u8() << 8)); }
};

class FuzzDrive final : public rig::modbus::RegisterTransport {
 public:
  explicit FuzzDrive(Input& in) : in_(in) {}
  std::vector<uint16_t> read(uint16_t addr, uint16_t n, const rig::CancelToken&, bool) override {
    return reply(addr, n, "read");
  }
  std::vector<uint16_t> read_input(uint16_t addr, uint16_t n, const rig::CancelToken&, bool) override {
    return reply(addr, n, "read input");
  }
  void write(uint16_t addr, const std::vector<uint16_t>&, const rig::CancelToken&, bool) override {
    if (in_.done()) throw ModbusError("write " + std::to_string(addr) + ": timeout", 0, true);
    const uint8_t c = in_.u8();
    if (c % 8 == 0) throw ModbusError("write: timeout", 0, true);
    if (c % 8 == 1) throw ModbusError("write: exception", static_cast<uint8_t>(1 + (c >> 3) % 11), false);
  }
  std::string describe() const override { return "fuzz drive"; }

 private:
  std::vector<uint16_t> reply(uint16_t addr, uint16_t n, const char* what) {
    if (in_.done()) throw ModbusError(std::string(what) + " " + std::to_string(addr) + ": timeout", 0, true);
    const uint8_t c = in_.u8();
    if (c % 16 == 0) throw ModbusError(std::string(what) + ": timeout", 0, true);
    if (c % 16 == 1) throw ModbusError(std::string(what) + ": exception", static_cast<uint8_t>(1 + (c >> 4) % 11), false);
    std::vector<uint16_t> out(n);
    for (auto& v : out) v = in_.u16();
    return out;
  }
  Input& in_;
};

const rig::modbus::DriveMap& cia402_map() {
  static const rig::modbus::DriveMap m =
      rig::modbus::load_drive_map(std::string(RIG_SOURCE_DIR) + "/drives/generic-cia402.toml");
  return m;
}

// Runs a motion call; a fault it reports must state the stop's fate, or that the move was
// refused before anything was written ("; nothing sent": no halt is owed then; also a device that
// is not the configured drive), or that another master commands the table ("no halt sent by this
// client": its motion is not halted over, since session 24; the harness had not been told, and a
// clean-clone fuzz run found it). "<stop> not sent: <why>": a client that never identified its
// drive sends no stop into a device that reads as another map, and "no halt needed: ..." where
// the CiA 402 drive's power stage is off (session 26).
template <class F>
void motion(F f) {
  try {
    f();
  } catch (const rig::HardwareError& e) {
    const std::string m = e.what();
    if (std::getenv("FUZZ_MODBUS_VERBOSE")) std::fprintf(stderr, "%s\n", m.c_str());
    const bool refused_first = m.ends_with("; nothing sent");
    RIG_FUZZ_CHECK(m.find("halt delivered to the drive") != std::string::npos ||
                   m.find(" not delivered (") != std::string::npos || m.find(" not confirmed (") != std::string::npos || m.find(" not sent: ") != std::string::npos || m.find(" not sent (") != std::string::npos ||
                   m.find("; no halt needed: ") != std::string::npos ||
                   m.find("; no halt sent by this client: another master commands the table") != std::string::npos ||
                   refused_first);
    throw;
  }
}

void check_status(const rig::TableStatus& s) {
  RIG_FUZZ_CHECK(std::isfinite(s.actual_deg));
  RIG_FUZZ_CHECK(std::isfinite(s.target_deg));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  Input in{data, size};
  const uint8_t head = in.u8();
  rig::SimClock clock;
  rig::modbus::TableOptions opt;
  opt.home_timeout_s = 5;  // bounded simulated waits keep an execution short
  opt.move_timeout_s = 5;
  std::unique_ptr<rig::RotaryTable> table;
  std::unique_ptr<FuzzDrive> drive = std::make_unique<FuzzDrive>(in);
  if (head & 1)
    table = std::make_unique<rig::modbus::Cia402Table>(std::move(drive), cia402_map(), clock, opt);
  else
    table = std::make_unique<rig::modbus::TableClient>(std::move(drive), clock, opt);
  const rig::CancelToken never;
  for (int call = 0; call < 8 && !in.done(); ++call) {
    const uint8_t op = in.u8();
    rig::fuzz::expect_only_rig_errors([&] {
      switch (op % 6) {
        case 0: check_status(table->status()); break;
        case 1: motion([&] { table->home(never); }); break;
        case 2: {
          const double deg = static_cast<double>(static_cast<int16_t>(in.u16())) / 64.0;
          motion([&] { table->move_to(deg, never); });
          break;
        }
        case 3: table->stop(); break;
        case 4: table->quick_stop(); break;
        case 5:
          if (auto* t = dynamic_cast<rig::modbus::TableClient*>(table.get())) t->reset_alarm(never);
          break;
      }
    });
  }
  RIG_FUZZ_CHECK(!table->describe().empty());
  return 0;
}
