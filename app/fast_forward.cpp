#include "app/fast_forward.hpp"
#include "rig/core/json_unique.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <vector>

#include <nlohmann/json.hpp>

#include "procedures/acceptance/procedure.hpp"
#include "procedures/acceptance/state.hpp"

namespace rig::cli {

namespace fs = std::filesystem;

namespace {

nlohmann::json read_checkpoint(const std::string& run_dir) {
  std::ifstream in(Executive::checkpoint_path(run_dir));
  if (!in) return nlohmann::json();
  return parse_json_unique_keys(in);
}

// The first field where the replay's record of a phase differs from the checkpoint's, or "".
// Both come from the same to_json (doubles written with round-trip precision), so equal
// values compare equal exactly.
std::string first_difference(const nlohmann::json& replay, const nlohmann::json& checkpoint, const std::string& path) {
  if (replay.is_object()) {
    // In the record's order: "runs" is keyed "1".."12", which JSON sorts "1", "10", "11", "12",
    // "2" (a review: a difference in run 3 was reported at run 10).
    std::vector<std::string> keys;
    for (const auto& [k, v] : replay.items()) keys.push_back(k);
    const auto number = [](const std::string& k) {
      return !k.empty() && k.size() < 10 && std::all_of(k.begin(), k.end(), [](char c) { return c >= '0' && c <= '9'; })
                 ? std::stol(k)
                 : -1L;
    };
    if (std::all_of(keys.begin(), keys.end(), [&](const std::string& k) { return number(k) >= 0; }))
      std::sort(keys.begin(), keys.end(), [&](const std::string& x, const std::string& y) { return number(x) < number(y); });
    for (const std::string& k : keys) {
      if (!checkpoint.is_object() || !checkpoint.contains(k)) return path + "." + k + " (not in the checkpoint)";
      const std::string d = first_difference(replay[k], checkpoint[k], path + "." + k);
      if (!d.empty()) return d;
    }
    return "";
  }
  return replay == checkpoint ? "" : path + " (replay " + replay.dump() + ", checkpoint " + checkpoint.dump() + ")";
}

}  // namespace

void fast_forward_emulated(PhaseContext& ctx, const acceptance::Profile& p, const std::vector<std::string>& completed,
                           spdlog::logger& log) {
  // The replay's own procedure state, values and captures: nothing of it reaches the run's.
  acceptance::ProcedureState replay_state(p);
  const std::vector<Phase> phases = acceptance::build_phases(p, replay_state);
  MeasurementSet replay_values;
  acceptance::declare_values(p, phases, replay_values);
  const std::string scratch = ctx.out_dir + "/.fast-forward";
  fs::remove_all(scratch);  // left by a run killed during its own fast-forward
  fs::create_directories(scratch);
  // Gone however the replay ends (an abort during it left 11 MB behind: a review).
  struct RemoveScratch {
    std::string dir;
    ~RemoveScratch() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } remove_scratch{scratch};
  auto quiet = std::make_shared<spdlog::logger>("fast-forward");  // no sinks: the replay is not the run's log
  PhaseContext replay{ctx.dev, ctx.cancel, replay_values, scratch, quiet, nullptr, {}};
  std::size_t replayed = 0;
  if (ctx.progress && !completed.empty())
    ctx.progress->log("  emulated plant: replaying the completed recordings to rebuild its state at the checkpoint");
  for (const Phase& ph : phases) {
    if (std::find(completed.begin(), completed.end(), ph.id) == completed.end()) continue;
    if (ph.from_records) continue;  // computes from captures: leaves the devices alone
    log.info("fast-forward: replaying phase {} against the emulated plant (device time {:.3f} s)", ph.id,
             ctx.dev.clock.now_s());
    ph.run(replay);
    ++replayed;
    // Its captures are read no more (the check below compares the state, which holds what they
    // recorded): removed at once, so the replay needs room for one phase's, not the run's.
    std::error_code ec;
    std::vector<fs::path> used;
    for (fs::recursive_directory_iterator it(scratch, ec), end; !ec && it != end; it.increment(ec))
      if (it->is_regular_file(ec)) used.push_back(it->path());
    for (const fs::path& f : used) fs::remove(f, ec);
  }
  fs::remove_all(scratch);
  const nlohmann::json cp = read_checkpoint(ctx.out_dir);
  const nlohmann::json mine = acceptance::to_json(replay_state.slot());
  std::string diff;
  for (const char* part : {"runs", "in_run", "raw", "loop_test"})
    if (diff.empty() && mine.contains(part))
      diff = first_difference(mine[part], cp.is_object() && cp.contains("state") ? cp["state"].value(part, nlohmann::json())
                                                                                 : nlohmann::json(),
                              std::string("state.") + part);
  if (!diff.empty()) {
    log.warn("fast-forward: the replay does not reproduce {}: {}; the recordings were not made by this build's "
             "emulated plant with this seed (another build, or captures edited since), so the resumed passport will "
             "differ from an uninterrupted run's",
             Executive::checkpoint_path(ctx.out_dir), diff);
    return;
  }
  log.info("fast-forward: {} recorded phase(s) replayed to device time {:.3f} s; their recordings match the "
           "checkpoint bit for bit",
           replayed, ctx.dev.clock.now_s());
}

}  // namespace rig::cli
