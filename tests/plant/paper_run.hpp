// The calibration harness: the shipped acceptance procedure (`rig run --plant emulated`,
// a real child process) on the emulated DUT, one seed at a time, and what its passport
// and analysis.json say. The calibration test and bench/plant/dut_calibrate read the
// emulated DUT's calibration table from these, so the table measures the procedure that
// ships -- the sign rule of (3)/(4), the drift it removes, its in-run B and Allan phases --
// not a copy of it.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <toml++/toml.h>

namespace rig::plant::calib {

struct RunSpec {
  uint64_t seed = 1;                       // [plant] seed
  std::string base = "paper";              // the built-in profile the run starts from
  const toml::table* dut = nullptr;        // [plant.dut] overrides, may be null
  std::string taus;                        // [analysis] taus; empty = the profile's
};

struct PaperRun {
  uint64_t seed = 0;
  nlohmann::json passport;  // passport.json
  nlohmann::json analysis;  // analysis.json
  // A passport value (passport units), nullopt when the run reported it null.
  std::optional<double> value(const std::string& name) const;
};

// Runs `rig` (the binary at `rig_binary`) on the emulated plant in a fresh folder under
// the system's temporary directory, reads the two files and removes the folder (the
// paper profile's captures are about 100 MB). A run that ends with anything but exit 0
// or 1 (1: a value outside its profile limits, still a complete passport) throws
// std::runtime_error with rig's stderr.
PaperRun run_rig(const std::string& rig_binary, const RunSpec& spec);
// Several seeds, `parallel` runs at a time, results in the order of `seeds`.
std::vector<PaperRun> run_seeds(const std::string& rig_binary, RunSpec spec, const std::vector<uint64_t>& seeds,
                                int parallel = 2);

}  // namespace rig::plant::calib
