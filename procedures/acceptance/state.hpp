// The acceptance procedure's state: what its phases hand on to each other
// (run means, bias, the captures recorded, the analysis curves), typed, with
// one JSON form used by the checkpoint and by analysis.json.
//
// Per DUT: a fixture with N DUTs in one run holds one DutState per slot (the
// table moves them together; each has its own link, captures and values).
// Today's fixture has one slot; the checkpoint's "state" is slot 0's object
// (the same keys as before the state was typed, so older checkpoints resume).
#pragma once
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "procedures/acceptance/loop_record.hpp"
#include "procedures/acceptance/profile.hpp"
#include "procedures/acceptance/record.hpp"
#include "rig/executive/executive.hpp"

namespace rig::acceptance {

// A bring-up step the DUT could not take (a DUT without a command channel), and why.
struct SkippedStep {
  std::string step, reason;
};

struct DutIdentity {
  std::string serial, firmware;
  std::optional<double> temperature_c;  // null: the DUT could not be asked
  std::vector<SkippedStep> skipped;     // bring-up steps skipped (passport.json "skipped")
};

// One run of procedure A (formulas (3), (4) take its mean).
struct RunMean {
  std::size_t index = 0;  // 1-based, in the profile's order
  Orientation orientation = Orientation::U10;
  Recorded rec;
};

struct BiasState {
  double bias = 0, base_error = 0;
  int sign_u10 = +1;  // sign with which g_dA enters x10 (docs/method.md, after (4))
};

// B by the Russian method for one block length (GOST R 8.736 block means).
struct GostBlock {
  double block_s = 0;
  std::vector<double> means_g;
  std::optional<double> b_g;
};

struct DutState {
  std::optional<DutIdentity> dut;       // bring-up (every start)
  std::map<std::size_t, RunMean> runs;  // runNN phases, by index
  std::optional<BiasState> bias;        // bias phase
  std::optional<Recorded> in_run;       // in-run phase
  std::optional<std::vector<GostBlock>> in_run_blocks;  // in-run-b phase
  std::optional<Recorded> raw;          // raw phase
  std::optional<nlohmann::json> analysis;  // allan phase: the math's JSON views (oadev, noise_terms, psd, timeseries)
  std::optional<LoopRecord> loop_test;     // loop phase: what the loop test recorded
  std::optional<nlohmann::json> loop;      // loop-figures phase: the loop figures' JSON view
  // The rig's clock when the last phase that used the devices ended (analysis.json's
  // device_time_s): kept with the recordings, so a resume that only computes does not move it.
  std::optional<double> device_time_s;
  // This attempt's captures that a stop left incomplete (relative to the run folder). Not in the
  // checkpoint: only the ending reads it, so that the final seal vouches for what this attempt
  // wrote (an aborted sealed run failed `rig verify`, its partial capture "added after the seal").
  std::vector<std::string> partial_captures;

  std::string serial() const { return dut ? dut->serial : std::string(); }
  // The captures recorded (relative to the run folder), in the order of the procedure.
  std::vector<std::string> captures() const;
};

nlohmann::json to_json(const Recorded& r);
nlohmann::json to_json(const DutState& s);
// Throws std::invalid_argument naming the field ("state.bias.sign_u10: expected an integer, found null").
DutState dut_state_from_json(const nlohmann::json& j);

// The procedure's PhaseState. restore() also checks the state against the phases
// marked completed (each must have left its part, and no part is there that no completed
// phase wrote) and each recording against its capture (the field's own capture, of that
// phase, orientation, rate and DUT, closed and undamaged, the samples a recording of that
// length holds with the record's means, a counter that only goes forward, losses within the
// profile's limit and at least what the counter shows). The values computed from these records are
// computed again on a resume (Phase::from_records), so none is taken from the file.
class ProcedureState final : public PhaseState {
 public:
  explicit ProcedureState(const Profile& p) : profile_(p) {}
  DutState& slot(std::size_t i = 0) { return slots_.at(i); }
  const DutState& slot(std::size_t i = 0) const { return slots_.at(i); }
  std::size_t slots() const { return slots_.size(); }

  nlohmann::json save() const override;
  void restore(const nlohmann::json& j, const std::vector<std::string>& completed, const std::string& run_dir) override;
  void forget(const std::string& phase_id) override;
  bool holds(const std::string& phase_id) const override;
  // Slot 0's recording in `file` (a capture, or the loop test's records; relative to the run
  // folder) checked against the file as restore() checks it: the problem, "" when it holds. The
  // run's end asks it where a record's file stamp moved (a touch, a network file system's own
  // times) before it takes the record for changed.
  std::string recording_problem(const std::string& file, const std::string& run_dir) const;

 private:
  // What a completed recording must be: its phase id, orientation, length and DUT.
  struct Recording {
    std::string phase_id;
    Orientation orientation;
    double seconds;
    std::string serial;
  };
  // The profile's recordings, as restore() and recording_problem() alike hold a capture to them.
  Recording run_recording(std::size_t index, const std::string& serial) const {
    return {run_phase_id(index, profile_.order[index - 1]), profile_.order[index - 1], profile_.run_s, serial};
  }
  Recording in_run_recording(const std::string& serial) const {
    return {in_run_phase_id(profile_), profile_.in_run_orientation, profile_.in_run_s, serial};
  }
  Recording raw_recording(const std::string& serial) const {
    return {raw_phase_id(profile_), profile_.raw_orientation, profile_.raw_s, serial};
  }
  void check_capture(Recorded& r, const std::string& field, const std::string& run_dir, const Recording& want) const;
  const Profile& profile_;
  std::vector<DutState> slots_ = std::vector<DutState>(1);
  // A checkpoint of a version before the loop test's records were kept marks `loop` completed
  // with its figures only: that phase is not held and runs again (Executive::read_checkpoint).
  bool loop_figures_only_ = false;
  bool loop_not_run_ = false;  // `loop` completed without a loop test: the DUT is asked again
};

}  // namespace rig::acceptance
