// The loop test's records (docs/can-protocol.md "Loop test"): loop-test.csv in the run folder,
// every value as the DUT sent it, and LoopRecord, its description in the checkpoint's state. The
// `loop` phase writes both; `loop-figures` reads the figures off the file, and a resume checks
// the description against the file before any device opens, as it checks each recording against
// its capture (ProcedureState::restore).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rig/core/dut_link.hpp"

namespace rig::acceptance {

inline constexpr const char* kLoopTestFile = "loop-test.csv";  // relative to the run folder

struct LoopRecord {
  bool supported = false;  // false: the DUT has no loop test (or it is switched off)
  std::string reason;      // why not, when !supported
  std::string file;        // relative to the run folder, when supported
  double rate_hz = 0, amplitude_g = 0;
  std::vector<std::size_t> samples, pre_samples;  // per step
  std::vector<bool> saturated;                    // per step: the DUT's loop saturated
  uint32_t crc32 = 0;                             // of the file's bytes as written (zlib's CRC-32)
};

nlohmann::json to_json(const LoopRecord& r);
uint32_t crc32_of(const std::string& bytes);  // zlib's CRC-32

// The raw records as loop-test.csv: comment lines stating the steps, the amplitude, the loop
// rate and the steps in which the DUT's loop saturated ("PWM saturated" before 2026-12-07, read too), the header, then one line per sample:
// step, index, t_s (from the step), x_g, y_g. Every number the figures depend on is written as
// the shortest decimal that reads back to the same double.
std::string loop_test_csv(const LoopTestResponse& r);

// What a LoopRecord says of the records `csv` holds (the loop phase's, with the file's CRC-32).
LoopRecord loop_record_of(const LoopTestResponse& r, const std::string& csv);

// The records of the loop-test.csv at `path`: its bytes, read once, must have the CRC-32 `rec`
// holds (ConfigError naming state.loop_test.crc32 otherwise), and are then parsed as they are,
// so what the figures are computed from is what was checked (a file swapped in between is not
// read). The file must state exactly what `rec` describes (steps, samples and samples before the
// step of each, amplitude, rate, saturation): anything else is a ConfigError naming file:line
// and the value.
LoopTestResponse read_loop_test_csv(const std::string& path, const LoopRecord& rec);
std::string loop_test_bytes(const std::string& path, const LoopRecord& rec);  // the CRC-checked bytes
LoopTestResponse parse_loop_test_csv(const std::string& text, const std::string& path, const LoopRecord& rec);

// The checkpoint's record against the run folder's file: its name, its bytes to the CRC-32 and
// everything the file states (read_loop_test_csv). std::invalid_argument naming the field
// ("state.loop_test.crc32: ...") otherwise. A DUT without a loop test recorded nothing: the
// folder must hold no records then.
void check_loop_record(const LoopRecord& r, const std::string& run_dir);

}  // namespace rig::acceptance
