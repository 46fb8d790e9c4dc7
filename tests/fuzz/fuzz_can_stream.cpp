// CAN frames from the bus as the rig sees them: every frame through the protocol decoder, every
// stream half through the reassembly (reorder window, 24-bit widening, gaps, duplicates).
// Input: 13-byte records (u32 id with bit 31 = extended, u8 len, 8 data bytes); one extra
// leading byte picks the reorder window. Invariants: delivered samples are in strictly
// increasing order of their widened sequence, and the link's count of delivered samples
// equals what was popped.
#include <array>
#include <cstring>
#include <variant>

#include "firmware_link/protocol.hpp"
#include "firmware_link/reassembly.hpp"
#include "tests/fuzz/fuzz_target.hpp"

using namespace rig;
using namespace rig::link;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  StreamReassembler r(1 + data[0] % 16);
  ++data, --size;
  std::array<Sample, 64> out{};
  uint64_t popped = 0;
  bool have_last = false;
  uint32_t last_seq = 0;
  auto drain = [&] {
    for (std::size_t n; (n = r.pop(out)) > 0;) {
      for (std::size_t i = 0; i < n; ++i) {
        // seq is the widened counter modulo 2^32: consecutive deliveries differ by 1..2^31
        if (have_last) RIG_FUZZ_CHECK(out[i].seq - last_seq >= 1 && out[i].seq - last_seq < (1u << 31));
        last_seq = out[i].seq;
        have_last = true;
      }
      popped += n;
    }
  };
  for (; size >= 13; data += 13, size -= 13) {
    CanFrame f;
    uint32_t id;
    std::memcpy(&id, data, 4);
    f.extended = (id >> 31) != 0;
    f.id = id & (f.extended ? 0x1FFFFFFFu : 0x7FFu);
    f.len = static_cast<uint8_t>(data[4] % 9);
    std::memcpy(f.data.data(), data + 5, 8);
    const Decoded d = decode(f);
    RIG_FUZZ_CHECK(std::holds_alternative<std::monostate>(d.msg) || d.error.empty());
    if (const auto* h = std::get_if<StreamHalf>(&d.msg)) {
      r.push(*h);
      if (data[5] & 1) drain();
    }
    (void)to_candump(f);
  }
  r.flush();
  drain();
  RIG_FUZZ_CHECK(r.stats().received == popped);
  return 0;
}
