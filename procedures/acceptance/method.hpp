// The acceptance procedure's computations as pure functions: vectors in, figures out,
// no I/O, no run state. The phases (procedure.cpp) call them on what they recorded; the
// tests and the emulated DUT's noise studies call the same functions, so what they
// measure is what the passport measures.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "analysis/allan.hpp"
#include "analysis/noise_terms.hpp"
#include "procedures/acceptance/profile.hpp"

namespace rig::acceptance {

// What the Allan phase (procedure C) takes from the profile's [procedure] and [analysis].
struct AllanSettings {
  double rate_hz;
  std::string taus;       // the tau grid (analysis::parse_tau_grid)
  double confidence;      // of the deviation's bounds
  double r_min_record_s;  // the record R asks for (a shorter one's R says so in its reason)
};
AllanSettings allan_settings(const Profile& p);

struct AllanChannel {
  std::vector<analysis::DevPoint> oadev;
  analysis::NoiseTerms terms;
};

// One channel of procedure C: the overlapping Allan deviation of the record (frequency
// data at rate_hz) on the profile's tau grid, and the noise terms fitted to it (the
// paper's polynomial-segment B and the IEEE 952 weighted fit; docs/analysis.md).
// `poll` (may be empty) is called between chunks of work; it throws to abandon the computation
// (the phase passes its cancel token, so an abort is taken within a chunk).
AllanChannel allan_channel_terms(const std::vector<double>& record, const AllanSettings& s,
                                 const std::function<void()>& poll = {});

}  // namespace rig::acceptance
