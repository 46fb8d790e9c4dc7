// --inject: faults the emulated plant plays at a device time (tests, campaigns and technicians'
// training), parsed and checked before anything is written or any device opens.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "rig/core/cancel.hpp"

namespace rig::plant {
class EmulatedPlant;
}
namespace spdlog {
class logger;
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

// The sample losses (drop@SEQ:COUNT) among --inject's values, in order: the faults run.json keeps
// and a resume repeats; signals and e-stops are never repeated.
std::vector<std::string> sample_losses(const std::vector<std::string>& inject);

// The timed faults (estop@T, sigint@T, ...) at a device time well past `planned_s`, the plan's
// device time (over 1.25 times it and a minute: bring-up is not in it), each as a note: such a fault fires only if the run takes longer than planned (a review:
// estop@1e9 ran to PASS, exit 0, the dry run silent). Said before the run; the run says after it
// whether the fault fired (say_faults_that_did_not_fire).
std::vector<std::string> faults_past_the_plan(const std::vector<Injection>& inj, double planned_s);

// Arms the faults on the plant. Returns the signal asked for at the end, or 0. `taken`: the run's
// cancel token, which the process's signal watcher trips; a signal at T holds the plant at T
// until it is taken.
int apply_injections(plant::EmulatedPlant& w, const std::vector<Injection>& inj, const CancelToken& taken);

// Each fault that never met the run, as an error line (a test harness running with --quiet sees
// it too): one timed past the run's end, or a loss in samples the DUT never streamed. Otherwise a
// test of it passes for nothing (reviews: sigint@229 on a run of 228 s of device time,
// drop@1000:5 between recordings, both exit 0 without a word). The caller's to call only after a
// run that was not stopped and whose device time is whole. from_run_json: a resume's faults,
// repeated from run.json.
void say_faults_that_did_not_fire(plant::EmulatedPlant& w, const std::vector<Injection>& inj, bool from_run_json,
                                  spdlog::logger& log);

}  // namespace rig::cli
