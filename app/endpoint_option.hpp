// --modbus and --rtu checked as typed before the command runs, so the message names the option
// ("--modbus: Modbus TCP address 'localhost:99999': port out of range"): it said "command-line
// option: ..." or nothing of where (a technician's review). The same parsers as the hardware
// file's [table] modbus/rtu keys (rig/modbus/transport.hpp).
#pragma once
#include <string>

#include <CLI/CLI.hpp>

#include "rig/modbus/transport.hpp"

namespace rig::cli {

enum class EndpointOption {
  kDrive,   // `rig table --modbus`: as the hardware file's [table] modbus key (tcp:, rtu: or HOST:PORT), a port 1..65535
  kServe,   // `rig plant serve --modbus`: HOST:PORT, port 0 picking a free one
  kSerial,  // --rtu: DEVICE[,BAUD[,P,D,S]]
};

inline CLI::Validator modbus_endpoint_option(EndpointOption kind) {
  return CLI::Validator(
      [kind](std::string& v) -> std::string {
        try {
          if (kind == EndpointOption::kSerial) {
            (void)modbus::parse_rtu(v);
          } else if (kind == EndpointOption::kServe) {
            (void)modbus::parse_tcp(v);
          } else if (const modbus::Endpoint ep = modbus::parse_endpoint(v);
                     ep.kind == modbus::Endpoint::Kind::kTcp && ep.port == 0) {
            return "Modbus TCP address '" + v + "': port 0 is no drive's port (1..65535)";
          }
          return "";
        } catch (const std::exception& e) {
          return e.what();
        }
      },
      kind == EndpointOption::kSerial ? "DEVICE[,BAUD[,P,D,S]]" : "HOST:PORT");
}

}  // namespace rig::cli
