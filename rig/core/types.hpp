// Value types shared across the seams: samples, orientation, device status.
#pragma once
#include <cstdint>
#include <string>

namespace rig {

// Status bits a DUT sample carries (firmware-defined; see docs/can-protocol.md).
namespace sample_status {
inline constexpr uint32_t kFilterOn = 1u << 0;      // y(t) is W_f(z) applied to x(t)
inline constexpr uint32_t kSaturated = 1u << 1;     // loop output at range limit
inline constexpr uint32_t kLoopFault = 1u << 2;     // regulator reports a fault
inline constexpr uint32_t kGapBefore = 1u << 8;     // rig-side: samples were lost before this one
}  // namespace sample_status

// One output sample of the DUT as the rig receives it (1 kHz).
struct Sample {
  uint32_t seq = 0;     // DUT's free-running sample counter (wraps modulo 2^32 on the link's widening)
  float x_g = 0;        // unfiltered output x(t), g
  float y_g = 0;        // output filter W_f(z) applied, y(t), g
  uint32_t status = 0;  // sample_status bits
};

enum class Orientation { U10, U20 };
inline const char* to_string(Orientation o) { return o == Orientation::U10 ? "U10" : "U20"; }

}  // namespace rig
