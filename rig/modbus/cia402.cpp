#include "rig/modbus/cia402.hpp"

namespace rig::modbus::cia402 {

State decode_state(uint16_t s) {
  // Masks and values from the statusword table of IEC 61800-7-201.
  if ((s & 0x4F) == 0x00) return State::kNotReadyToSwitchOn;
  if ((s & 0x4F) == 0x40) return State::kSwitchOnDisabled;
  if ((s & 0x6F) == 0x21) return State::kReadyToSwitchOn;
  if ((s & 0x6F) == 0x23) return State::kSwitchedOn;
  if ((s & 0x6F) == 0x27) return State::kOperationEnabled;
  if ((s & 0x6F) == 0x07) return State::kQuickStopActive;
  if ((s & 0x4F) == 0x0F) return State::kFaultReactionActive;
  if ((s & 0x4F) == 0x08) return State::kFault;
  // Any other pattern is not a state of the standard; the client treats it as
  // "not ready" and refuses to guess.
  return State::kNotReadyToSwitchOn;
}

bool is_state(uint16_t s) {
  const uint16_t a = s & 0x4F, b = s & 0x6F;
  return a == 0x00 || a == 0x40 || b == 0x21 || b == 0x23 || b == 0x27 || b == 0x07 || a == 0x0F || a == 0x08;
}

uint16_t state_bits(State s) {
  switch (s) {
    case State::kNotReadyToSwitchOn: return 0x00;
    case State::kSwitchOnDisabled: return 0x40;
    case State::kReadyToSwitchOn: return 0x21 | sw::kVoltageEnabled;
    case State::kSwitchedOn: return 0x23 | sw::kVoltageEnabled;
    case State::kOperationEnabled: return 0x27 | sw::kVoltageEnabled;
    case State::kQuickStopActive: return 0x07 | sw::kVoltageEnabled;
    case State::kFaultReactionActive: return 0x0F;
    case State::kFault: return 0x08;
  }
  return 0;
}

std::string state_name(State s) {
  switch (s) {
    case State::kNotReadyToSwitchOn: return "Not ready to switch on";
    case State::kSwitchOnDisabled: return "Switch on disabled";
    case State::kReadyToSwitchOn: return "Ready to switch on";
    case State::kSwitchedOn: return "Switched on";
    case State::kOperationEnabled: return "Operation enabled";
    case State::kQuickStopActive: return "Quick stop active";
    case State::kFaultReactionActive: return "Fault reaction active";
    case State::kFault: return "Fault";
  }
  return "?";
}

std::string error_code_text(uint16_t code) {
  switch (code) {
    case 0x0000: return "no error";
    case 0x2310: return "continuous over-current";
    case 0x3210: return "DC link over-voltage";
    case 0x3220: return "DC link under-voltage";
    case 0x4310: return "drive over-temperature";
    case 0x5441: return "enable input (safe torque off) open";
    case 0x7305: return "incremental encoder fault";
    case 0x8611: return "following error";
    case 0x8612: return "reference limit (limit switch)";
    case 0x8A00: return "homing error";
    case 0xFF01: return "emergency stop";
    default: break;
  }
  switch (code >> 12) {
    case 0x2: return "current fault";
    case 0x3: return "voltage fault";
    case 0x4: return "temperature fault";
    case 0x5: return "device hardware fault";
    case 0x6: return "device software fault";
    case 0x7: return "additional modules fault";
    case 0x8: return "monitoring fault";
    case 0x9: return "external error";
    default: return "manufacturer specific";
  }
}

}  // namespace rig::modbus::cia402
