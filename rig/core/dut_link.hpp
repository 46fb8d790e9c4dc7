// DUT link seam: the DUT's firmware streams samples and answers commands.
// Real backend: CAN (firmware_link/, SocketCAN). Emulated: the same CAN client to
// the firmware emulator on an in-process bus (plant/emulated).
#pragma once
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "design/filter_config.hpp"  // Biquad, FilterConfig: the filter the link sets
#include "rig/core/cancel.hpp"
#include "rig/core/types.hpp"

namespace rig {

struct DutInfo {
  std::string serial;
  std::string firmware;
  double temperature_c = 0.0;
  double output_rate_hz = 1000.0;
};

// Stream health counted by the link's reassembly (sequence numbers).
struct LinkStats {
  uint64_t received = 0;    // samples delivered
  uint64_t gaps = 0;        // gap events
  uint64_t lost = 0;        // samples missing in gaps
  uint64_t duplicates = 0;  // dropped duplicates / late frames
  std::vector<std::pair<uint64_t, uint64_t>> gap_list;  // (first missing seq, count), first 1000
};

class DutLink {
 public:
  virtual ~DutLink() = default;
  virtual DutInfo info(const CancelToken& cancel) = 0;
  virtual void start_stream(const CancelToken& cancel) = 0;
  virtual void stop_stream() noexcept = 0;  // safe-state path: never throws
  // Fills `out` with the next samples of the stream, in sequence order. Returns
  // the number written (== out.size() unless the stream is silent longer than
  // the link's silence limit, which throws HardwareError). Samples after a gap
  // carry sample_status::kGapBefore.
  virtual std::size_t read(std::span<Sample> out, const CancelToken& cancel) = 0;
  virtual void set_filter(const FilterConfig& f, const CancelToken& cancel) = 0;
  virtual FilterConfig get_filter(const CancelToken& cancel) = 0;
  virtual LinkStats stats() const = 0;
  virtual void reset_stats() = 0;
  virtual std::string describe() const = 0;
};

}  // namespace rig
