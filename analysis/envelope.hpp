// The output over time in a form a reader can use: a long record (a 60 min capture at 1 kHz
// holds 3.6 million samples and, on a quantised output, only a few distinct levels per second)
// cut into equal blocks, each summarised by its mean and its raw minimum and maximum.
#pragma once
#include <cstddef>
#include <span>
#include <vector>

namespace rig::analysis {

struct Envelope {
  double block_s = 0;               // block length (the last block may be shorter)
  std::vector<double> t_s;          // middle of each block, from the record's start
  std::vector<double> mean, min, max;
};

// At most `max_blocks` blocks of ceil(n / max_blocks) samples each. Empty for an empty record
// or a non-positive rate.
Envelope block_envelope(std::span<const double> x, double rate_hz, std::size_t max_blocks);

}  // namespace rig::analysis
