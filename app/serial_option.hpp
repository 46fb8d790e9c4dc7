// --serial (rig run, rig capture import): the serial goes into the passport, JUnit, the
// history, the run folder's name and a capture's header, so it is held to what the DUT
// protocol can report (firmware_link/protocol.hpp) before anything is opened or written.
#pragma once
#include <string>

#include <CLI/CLI.hpp>

#include "firmware_link/protocol.hpp"
#include "rig/core/escape.hpp"

namespace rig::cli {

inline CLI::Validator serial_validator() {
  return CLI::Validator(
      [](std::string& v) -> std::string {
        const std::string why = link::serial_problem(v);
        if (why.empty()) return {};
        return "'" + shown_ascii(v) + "': " + why;  // its control bytes shown, not sent
      },
      "");
}

}  // namespace rig::cli
