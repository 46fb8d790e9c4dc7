// The words `rig` puts before an error's message on stderr, by the error's kind. main.cpp's last
// word on a thrown error and a command that says one and goes on (a dry run finding the history
// locked) say it alike, so a script keying on "rig: configuration error: " finds both.
#pragma once
#include <exception>

#include "rig/core/errors.hpp"

namespace rig::cli {

// Most derived kind first: InputError and InUseError are ConfigErrors, NotReadyError a HardwareError.
inline const char* error_prefix(const std::exception& e) {
  if (dynamic_cast<const InputError*>(&e)) return "rig: input error: ";
  if (dynamic_cast<const InUseError*>(&e)) return "rig: in use: ";
  if (dynamic_cast<const ConfigError*>(&e)) return "rig: configuration error: ";
  if (dynamic_cast<const AbortedError*>(&e)) return "rig: ";
  if (dynamic_cast<const NotReadyError*>(&e)) return "rig: not ready: ";
  if (dynamic_cast<const HardwareError*>(&e)) return "rig: hardware fault: ";
  return "rig: error: ";
}

}  // namespace rig::cli
