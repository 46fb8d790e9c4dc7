// --inject: faults the emulated plant plays at a device time (tests, campaigns and technicians'
// training), parsed and checked before anything is written or any device opens.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace rig::plant {
class EmulatedPlant;
}

namespace rig::cli {

// Emulated-plant fault injection (tests, campaigns and technicians' training):
// estop@T, sigint@T / sigterm@T / sigkill@T (a real signal to this process at device time T:
// the campaigns' random points, reproducible to the sample), drop@SEQ:COUNT, and
// sigint@end / sigterm@end: the signal after the last phase, before the passport is written
// (the late signal of issue 13).
struct Injection {
  enum class Kind { Estop, Signal, Drop, SignalAtEnd } kind = Kind::Estop;
  double at_s = 0;  // Estop, Signal: device time
  int signal = 0;   // Signal, SignalAtEnd
  uint32_t seq = 0, count = 0;  // Drop
  std::string text;             // as given
};

// Every --inject checked before anything is written or any device opens (--dry-run included):
// a typo must not surface after the run folder exists, or after the hardware has opened.
// ConfigError naming the value.
std::vector<Injection> parse_injections(const std::vector<std::string>& inj);

// Arms the faults on the plant. Returns the signal asked for at the end, or 0.
int apply_injections(plant::EmulatedPlant& w, const std::vector<Injection>& inj);

}  // namespace rig::cli
