// The rotary table's Modbus register map (docs/table-registers.md), shared by
// the rig's client (rig/modbus) and the emulated drive (plant/table), so both
// ends agree on every address, bit and scale.
//
// Holding registers, 0-based PDU addresses; 32-bit values take two registers,
// high word first, and must be written in one request (function 16).
// Control/status words follow the CiA 402 manner (servo on, start on rising
// edge, home, halt, quick stop, alarm/fault reset on bit 7, halt on bit 8).
#pragma once
#include <cstdint>
#include <string>

namespace rig::modbus {

namespace reg {
inline constexpr uint16_t kControl = 0;       // RW u16  control word
inline constexpr uint16_t kStatus = 1;        // R  u16  status word
inline constexpr uint16_t kAlarmCode = 2;     // R  u16  alarm code, 0 = none
inline constexpr uint16_t kMapVersion = 3;    // R  u16  register map version (kMapVersionValue)
inline constexpr uint16_t kHeartbeat = 4;     // R  u32  +1 every 10 ms of drive time
inline constexpr uint16_t kActualPos = 6;     // R  i32  0.0001 deg
inline constexpr uint16_t kTargetPos = 8;     // RW i32  0.0001 deg
inline constexpr uint16_t kVelocity = 10;     // RW u32  profile velocity, 0.001 deg/s
inline constexpr uint16_t kAccel = 12;        // RW u32  profile acceleration = deceleration, 0.001 deg/s^2
inline constexpr uint16_t kInPosWindow = 14;  // RW u16  in-position window, 0.0001 deg
inline constexpr uint16_t kSettleTime = 15;   // RW u16  in-position settle time, ms
inline constexpr uint16_t kActualVel = 16;    // R  i32  0.001 deg/s
inline constexpr uint16_t kFollowErr = 18;    // R  i32  following error, 0.0001 deg
inline constexpr uint16_t kLimitNeg = 20;     // R  i32  soft travel limit, 0.0001 deg
inline constexpr uint16_t kLimitPos = 22;     // R  i32  soft travel limit, 0.0001 deg
inline constexpr uint16_t kMoveSeq = 24;      // R  u16  +1 on every accepted start (set-point acknowledge)
inline constexpr uint16_t kBlockEnd = 25;     // first address after the drive block [0, 25)

// Emulator-only maintenance block (absent on a real drive): fault injection and inputs.
inline constexpr uint16_t kSimFault = 100;    // RW u16  SimFault armed for the next move (or now)
inline constexpr uint16_t kSimFaultAt = 101;  // RW u16  where in the move it fires, per mille of the move time
inline constexpr uint16_t kSimInputs = 102;   // RW u16  bit0 e-stop pressed, bit1 interlock open
inline constexpr uint16_t kSimEnd = 103;

inline constexpr uint16_t kMapVersionValue = 1;
}  // namespace reg

// Scales of the integer registers.
inline constexpr double kPosScale = 1e4;    // counts per degree
inline constexpr double kVelScale = 1e3;    // counts per deg/s and per deg/s^2

namespace ctl {  // control word bits
inline constexpr uint16_t kServoOn = 1u << 0;     // level; a rising edge enables the servo
inline constexpr uint16_t kStart = 1u << 1;       // rising edge: move to TARGET_POS
inline constexpr uint16_t kHome = 1u << 2;        // rising edge: run the homing sequence
inline constexpr uint16_t kQuickStop = 1u << 3;   // rising edge: stop on the quick-stop ramp, hold
inline constexpr uint16_t kAlarmReset = 1u << 7;  // rising edge: clear the alarm if its cause is gone
inline constexpr uint16_t kHalt = 1u << 8;        // level: decelerate on the profile ramp and hold
inline constexpr uint16_t kAll = kServoOn | kStart | kHome | kQuickStop | kAlarmReset | kHalt;
}  // namespace ctl

namespace sts {  // status word bits
inline constexpr uint16_t kReady = 1u << 0;        // powered, no alarm, e-stop released, interlock closed
inline constexpr uint16_t kServoOn = 1u << 1;
inline constexpr uint16_t kMoving = 1u << 2;       // profile running or not yet settled
inline constexpr uint16_t kInPosition = 1u << 3;   // within the window for the settle time
inline constexpr uint16_t kHomed = 1u << 4;
inline constexpr uint16_t kHoming = 1u << 5;
inline constexpr uint16_t kAlarm = 1u << 6;
inline constexpr uint16_t kEstop = 1u << 7;
inline constexpr uint16_t kLimitPos = 1u << 8;
inline constexpr uint16_t kLimitNeg = 1u << 9;
inline constexpr uint16_t kInterlockOk = 1u << 10;
}  // namespace sts

namespace alarm {  // ALARM_CODE values
inline constexpr uint16_t kNone = 0x0000;
inline constexpr uint16_t kNotHomed = 0x0010;      // move refused: not homed
inline constexpr uint16_t kServoOff = 0x0011;      // move/home refused: servo off
inline constexpr uint16_t kNotReady = 0x0012;      // move/home refused: e-stop or interlock open
inline constexpr uint16_t kFollowing = 0x0021;     // following error over the limit
inline constexpr uint16_t kOverTravelPos = 0x0030;
inline constexpr uint16_t kOverTravelNeg = 0x0031;
inline constexpr uint16_t kDriveFault = 0x0040;    // power stage fault
inline constexpr uint16_t kEstop = 0x0050;         // emergency stop pressed
inline constexpr uint16_t kInterlock = 0x0051;     // interlock opened during motion
inline constexpr uint16_t kHomingFailed = 0x0060;
inline constexpr uint16_t kCommLost = 0x0070;      // no request within the comm timeout while moving
}  // namespace alarm

// Meaning of an alarm code ("following error"), "unknown alarm" otherwise.
std::string alarm_text(uint16_t code);
// Command refusals leave nothing moved or damaged, so a client may reset them
// on its own; every other alarm needs a technician (`rig table reset`).
bool alarm_safe_to_reset(uint16_t code);

// Emulator fault injection (reg::kSimFault).
enum class SimFault : uint16_t { kNone = 0, kOverTravel = 1, kFollowing = 2, kDriveFault = 3, kNoAnswer = 4 };

// Modbus exception codes (Modbus Application Protocol V1.1b3, section 7).
namespace exc {
inline constexpr uint8_t kNone = 0;
inline constexpr uint8_t kIllegalFunction = 1;
inline constexpr uint8_t kIllegalAddress = 2;
inline constexpr uint8_t kIllegalValue = 3;
inline constexpr uint8_t kDeviceFailure = 4;
inline constexpr uint8_t kBusy = 6;
inline constexpr uint8_t kGatewayPath = 10;    // gateway path unavailable
inline constexpr uint8_t kGatewayTarget = 11;  // gateway target device failed to respond
}  // namespace exc
std::string exception_text(uint8_t code);  // "illegal data address"

// 32-bit register pairs, high word first.
inline uint32_t join_u32(uint16_t hi, uint16_t lo) { return (static_cast<uint32_t>(hi) << 16) | lo; }
inline int32_t join_i32(uint16_t hi, uint16_t lo) { return static_cast<int32_t>(join_u32(hi, lo)); }
inline void split_u32(uint32_t v, uint16_t* out) {
  out[0] = static_cast<uint16_t>(v >> 16);
  out[1] = static_cast<uint16_t>(v & 0xFFFFu);
}
inline void split_i32(int32_t v, uint16_t* out) { split_u32(static_cast<uint32_t>(v), out); }

// A register space a Modbus server can serve: the emulated drive implements it,
// the libmodbus server and the in-process transport both call it. Return an
// exception code (exc::kNone on success).
class RegisterDevice {
 public:
  virtual ~RegisterDevice() = default;
  virtual uint8_t read_registers(uint16_t addr, uint16_t n, uint16_t* out) = 0;
  virtual uint8_t write_registers(uint16_t addr, const uint16_t* values, uint16_t n) = 0;
  // Function 04. A device without a separate input register space (the rig-v1
  // map) serves its holding registers there too.
  virtual uint8_t read_input_registers(uint16_t addr, uint16_t n, uint16_t* out) { return read_registers(addr, n, out); }
  // False while the device is injected "no answer": requests go unanswered.
  virtual bool answering() const = 0;
  // Injected slow answers: the server waits this long before replying.
  virtual double answer_delay_s() const { return 0.0; }
};

}  // namespace rig::modbus
