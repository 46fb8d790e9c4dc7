// Resume in emulation without losing a bit (issue 13, item 7). The emulated plant's state at a
// device time is a function of its seed, its profile and every command the rig sent it up to
// then; a resumed run rebuilds that state by driving a fresh plant through the same commands:
// after bring-up, the completed phases that use the devices are replayed against the plant
// (their captures go to a scratch folder and are deleted), so the phases still to run meet the
// plant, the device clock and the rig's own clients exactly as the uninterrupted run left them.
// Why a replay and not a saved snapshot or counter-based noise: docs/plant.md, "Resume".
#pragma once
#include <string>
#include <vector>

#include <spdlog/logger.h>

#include "procedures/acceptance/profile.hpp"
#include "rig/executive/executive.hpp"

namespace rig::cli {

// Replays, against `ctx.dev`, every phase in `completed` (Executive::read_checkpoint's) that
// uses the devices (the recordings; bias, in-run-b and allan only compute from files), then
// checks that the replay reproduced what `checkpoint.json` recorded of them (sample counts,
// losses, means bit for bit). A mismatch means this build's plant is not the one that wrote
// the checkpoint: logged as a warning (the resumed passport will then differ from an
// uninterrupted run's), never silently.
void fast_forward_emulated(PhaseContext& ctx, const acceptance::Profile& p, const std::vector<std::string>& completed,
                           spdlog::logger& log);

}  // namespace rig::cli
