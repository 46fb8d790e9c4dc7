// CiA 402 (IEC 61800-7-201) drive profile: the power drive state machine and
// the controlword/statusword bits of profile position and homing modes, shared
// by the rig's client (rig/modbus/cia402_client) and the emulated drive
// (plant/table/cia402_drive) so both ends read the standard the same way.
#pragma once
#include <cstdint>
#include <string>

namespace rig::modbus::cia402 {

// Object indices (IEC 61800-7-201, section 6 object dictionary).
namespace obj {
inline constexpr uint16_t kDeviceType = 0x1000;  // CiA 301: low word the device profile number
inline constexpr uint16_t kErrorCode = 0x603F;
inline constexpr uint16_t kControlword = 0x6040;
inline constexpr uint16_t kStatusword = 0x6041;
inline constexpr uint16_t kQuickStopOption = 0x605A;
inline constexpr uint16_t kModesOfOperation = 0x6060;
inline constexpr uint16_t kModesDisplay = 0x6061;
inline constexpr uint16_t kPositionActual = 0x6064;
inline constexpr uint16_t kVelocityActual = 0x606C;
inline constexpr uint16_t kTargetPosition = 0x607A;
inline constexpr uint16_t kHomeOffset = 0x607C;
inline constexpr uint16_t kProfileVelocity = 0x6081;
inline constexpr uint16_t kProfileAcceleration = 0x6083;
inline constexpr uint16_t kProfileDeceleration = 0x6084;
inline constexpr uint16_t kQuickStopDeceleration = 0x6085;
inline constexpr uint16_t kHomingMethod = 0x6098;
inline constexpr uint16_t kFollowingErrorActual = 0x60F4;
}  // namespace obj

// Device type 0x1000 (CiA 301): bits 0-15 the device profile (402 for a drive), bits 16-23 the
// profile's type (IEC 61800-7-201: 0x02 servo drive, 0x01 frequency converter, 0x03 stepper).
inline constexpr uint16_t kDeviceProfile = 402;
inline constexpr uint32_t kDeviceTypeServo = 0x00020000u | kDeviceProfile;

// Modes of operation (0x6060 / 0x6061).
inline constexpr int8_t kModeProfilePosition = 1;
inline constexpr int8_t kModeHoming = 6;

// Controlword 0x6040 bits.
namespace cw {
inline constexpr uint16_t kSwitchOn = 1u << 0;
inline constexpr uint16_t kEnableVoltage = 1u << 1;
inline constexpr uint16_t kQuickStop = 1u << 2;      // 0 = quick stop requested
inline constexpr uint16_t kEnableOperation = 1u << 3;
inline constexpr uint16_t kNewSetPoint = 1u << 4;    // profile position: rising edge takes 0x607A
inline constexpr uint16_t kHomingStart = 1u << 4;    // homing mode: rising edge starts homing
inline constexpr uint16_t kChangeImmediately = 1u << 5;
inline constexpr uint16_t kRelative = 1u << 6;
inline constexpr uint16_t kFaultReset = 1u << 7;     // rising edge
inline constexpr uint16_t kHalt = 1u << 8;
// Device control commands (table "Device control commands", bits 7,3,2,1,0).
inline constexpr uint16_t kShutdown = kEnableVoltage | kQuickStop;                       // 0110
inline constexpr uint16_t kCmdSwitchOn = kShutdown | kSwitchOn;                          // 0111
inline constexpr uint16_t kCmdEnableOperation = kCmdSwitchOn | kEnableOperation;         // 1111
inline constexpr uint16_t kDisableVoltage = 0;                                           // xx0x
inline constexpr uint16_t kCmdQuickStop = kEnableVoltage;                                // x01x
}  // namespace cw

// Statusword 0x6041 bits.
namespace sw {
inline constexpr uint16_t kReadyToSwitchOn = 1u << 0;
inline constexpr uint16_t kSwitchedOn = 1u << 1;
inline constexpr uint16_t kOperationEnabled = 1u << 2;
inline constexpr uint16_t kFault = 1u << 3;
inline constexpr uint16_t kVoltageEnabled = 1u << 4;
inline constexpr uint16_t kQuickStop = 1u << 5;        // 0 = quick stop active
inline constexpr uint16_t kSwitchOnDisabled = 1u << 6;
inline constexpr uint16_t kWarning = 1u << 7;
inline constexpr uint16_t kRemote = 1u << 9;
inline constexpr uint16_t kTargetReached = 1u << 10;
inline constexpr uint16_t kInternalLimit = 1u << 11;
inline constexpr uint16_t kSetPointAck = 1u << 12;     // profile position
inline constexpr uint16_t kHomingAttained = 1u << 12;  // homing
inline constexpr uint16_t kFollowingError = 1u << 13;  // profile position
inline constexpr uint16_t kHomingError = 1u << 13;     // homing
}  // namespace sw

// The power drive states (IEC 61800-7-201 figure "State machine").
enum class State {
  kNotReadyToSwitchOn,
  kSwitchOnDisabled,
  kReadyToSwitchOn,
  kSwitchedOn,
  kOperationEnabled,
  kQuickStopActive,
  kFaultReactionActive,
  kFault,
};

// Decodes the state from statusword bits 0-3, 5, 6 (the standard's masks 0x4F / 0x6F).
State decode_state(uint16_t statusword);
// Whether bits 0-3, 5, 6 form one of the standard's eight states (decode_state takes any other
// pattern as Not ready to switch on; a register that is not a CiA 402 statusword reads like that).
bool is_state(uint16_t statusword);
// The statusword bits 0-3, 5, 6 that encode `s` (voltage-enabled bit 4 is set
// from Ready to switch on up to Quick stop active).
uint16_t state_bits(State s);
std::string state_name(State s);  // "Operation enabled"

// Common 0x603F error codes (CiA 402 / CiA 301 emergency error codes); an
// unknown code is described by its class (the high byte), else "manufacturer specific".
std::string error_code_text(uint16_t code);

}  // namespace rig::modbus::cia402
