// The analysis the method runs unless told otherwise (docs/method.md procedure C): the defaults of
// the acceptance profile's [analysis] section and of `rig analyze`, kept here once so that
// neither copies them.
#pragma once
#include <string>

#include "analysis/allan.hpp"
#include "analysis/noise_terms.hpp"

namespace rig::analysis {

struct AnalysisOptions {
  std::string taus = "log:100";          // tau grid, parse_tau_grid's syntax
  double confidence = kOneSigma;         // of the Allan bounds: one sigma, Stable32's "0.683"
  double r_min_record_s = kRMinRecordS;  // the record R asks for (a shorter one's R says so)
};

}  // namespace rig::analysis
