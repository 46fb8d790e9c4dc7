// Recording a phase: stream the DUT for N seconds into a capture file while
// keeping online sums, with the link's gap accounting checked against the profile.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "procedures/acceptance/profile.hpp"
#include "rig/core/file_stamp.hpp"
#include "rig/executive/executive.hpp"

namespace rig::acceptance {

struct Recorded {
  std::string capture;  // path relative to the run folder
  uint64_t samples = 0;
  uint64_t lost = 0, gaps = 0, duplicates = 0;
  double mean_x = 0, mean_y = 0;
  int attempts = 1;
  // The capture as its writer closed it (or as a resume checked it), held in memory only: the
  // run's end compares the file with it (cmd_run's records check).
  std::optional<FileStamp> written;
};

// Moves the table to `o`, settles, records `seconds` into captures/<name>.cap.
// A capture losing more than the profile allows is retried (profile.retries)
// and then fails the phase with a HardwareError naming the gaps.
// `serial` goes into the capture header. A stop mid-recording, or a last attempt with too many
// losses, keeps what was recorded and names the capture in `partial` (a final seal vouches for
// it as this attempt wrote it).
Recorded position_and_record(PhaseContext& ctx, const Profile& p, Orientation o, double seconds,
                             const std::string& name, const std::string& serial,
                             std::vector<std::string>* partial = nullptr);

double table_angle(const Profile& p, Orientation o);

// The names a recording goes by: its phase id (also the capture's header `phase`) and its
// capture file, relative to the run folder. A resume ties each record to these.
std::string run_phase_id(std::size_t index, Orientation o);  // index 1-based: "run03-U10"
std::string in_run_phase_id(const Profile& p);                // "in-run-U10"
std::string raw_phase_id(const Profile& p);                   // "raw-U10"
std::string capture_rel(const std::string& phase_id);         // "captures/<phase_id>.cap"

}  // namespace rig::acceptance
