// Shared by the libFuzzer harnesses: the documented outcome of bad input is a rig error
// (ConfigError / HardwareError, which the program maps to exit 2 / 4 with a message naming
// the file and position). Any other exception escaping a reader is a finding: it would reach
// the user as a raw library message, so the harness lets it abort the process.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "rig/core/errors.hpp"

namespace rig::fuzz {

template <class F>
void expect_only_rig_errors(F&& f) {
  try {
    f();
  } catch (const ConfigError&) {
  } catch (const HardwareError&) {
  }
}

inline std::string_view as_text(const uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// A check that must hold for every input; a violation aborts (libFuzzer records the input).
[[noreturn]] void invariant_failed(const char* what, const char* file, int line);
#define RIG_FUZZ_CHECK(cond) ((cond) ? void(0) : ::rig::fuzz::invariant_failed(#cond, __FILE__, __LINE__))

}  // namespace rig::fuzz
