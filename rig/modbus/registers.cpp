#include "rig/modbus/registers.hpp"

namespace rig::modbus {

std::string alarm_text(uint16_t code) {
  switch (code) {
    case alarm::kNone: return "";
    case alarm::kNotHomed: return "move refused: not homed";
    case alarm::kServoOff: return "command refused: servo off";
    case alarm::kNotReady: return "command refused: e-stop or interlock open";
    case alarm::kFollowing: return "following error";
    case alarm::kOverTravelPos: return "over-travel, positive limit switch";
    case alarm::kOverTravelNeg: return "over-travel, negative limit switch";
    case alarm::kDriveFault: return "drive fault (power stage)";
    case alarm::kEstop: return "emergency stop";
    case alarm::kInterlock: return "interlock opened during motion";
    case alarm::kHomingFailed: return "homing failed: home switch not found";
    case alarm::kCommLost: return "communication lost while moving";
    default: return "unknown alarm";
  }
}

bool alarm_safe_to_reset(uint16_t code) {
  return code == alarm::kNotHomed || code == alarm::kServoOff || code == alarm::kNotReady;
}

std::string exception_text(uint8_t code) {
  switch (code) {
    case exc::kIllegalFunction: return "illegal function";
    case exc::kIllegalAddress: return "illegal data address";
    case exc::kIllegalValue: return "illegal data value";
    case exc::kDeviceFailure: return "server device failure";
    case 5: return "acknowledge";
    case exc::kBusy: return "server device busy";
    case 8: return "memory parity error";
    // A gateway (or a TCP server for one unit) answering for a unit id it has no device at.
    case exc::kGatewayPath: return "gateway path unavailable (no device at this unit id behind the gateway? check the unit id: [table] unit, --unit)";
    case exc::kGatewayTarget: return "gateway target failed to respond (no device at this unit id? check the unit id: [table] unit, --unit)";
    default: return "exception " + std::to_string(code);
  }
}

}  // namespace rig::modbus
