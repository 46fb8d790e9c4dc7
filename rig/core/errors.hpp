// Error types: each maps to one of the documented exit codes (docs/contracts.md).
#pragma once
#include <stdexcept>
#include <string>

namespace rig {

enum ExitCode : int {
  kExitPass = 0,        // every measurement passed
  kExitFail = 1,        // a measurement failed its limits
  kExitUsage = 2,       // usage or configuration error
  kExitAborted = 3,     // aborted (signal, e-stop)
  kExitHardware = 4,    // hardware or link fault
};

// Bad configuration or input: names what and where ("profiles/x.toml:12:3: ...").
struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// A record given to be read (`rig analyze`'s input) that cannot be read as one: exit 2 as a
// configuration error, said as what it is ("input error: y.txt:5: ...").
struct InputError : ConfigError {
  using ConfigError::ConfigError;
};
// A device another process holds (the station's table lock): exit 2 as a configuration error,
// said as what it is ("rig: in use: table ...: in use by pid 4711: rig table move 90").
struct InUseError : ConfigError {
  using ConfigError::ConfigError;
};
// A device or link failed (table alarm, dead link, CAN bus-off, capture gap limit).
struct HardwareError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// The device is sound but in a state the command cannot start from (a table not homed): exit 4
// as a fault, named "not ready" (a technician's review: "hardware fault" read as a broken drive).
struct NotReadyError : HardwareError {
  using HardwareError::HardwareError;
};
// The run's own records (a capture, the loop test's file) found changed after their writer closed
// them, by a phase computing from them: exit 4 as any fault, and no resume is offered, since a
// resume refuses such a folder (rig/executive: RunResult::records_changed).
struct RecordsChangedError : HardwareError {
  using HardwareError::HardwareError;
};
// The run was aborted on request (signal, e-stop); `what()` says by whom.
struct AbortedError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace rig
