// DBC text as a user or another tool writes it: the reader either returns a database or
// throws a ConfigError naming the line. Invariants: every signal of a parsed message fits
// in its message's payload, and a frame of every message decodes (both byte orders, up to
// 64 bytes) without reading outside the payload.
#include <algorithm>
#include <string>

#include "firmware_link/dbc.hpp"
#include "tests/fuzz/fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  rig::fuzz::expect_only_rig_errors([&] {
    const auto db = rig::link::Dbc::parse(std::string(rig::fuzz::as_text(data, size)), "fuzz.dbc");
    for (const auto& m : db.messages()) {
      RIG_FUZZ_CHECK(db.find(m.id, m.extended) == &m);
      for (const auto& s : m.signals) RIG_FUZZ_CHECK(rig::link::dbc_signal_fits(s, m.dlc));
      rig::link::CanFdFrame f;
      f.id = m.id;
      f.extended = m.extended;
      f.len = static_cast<uint8_t>(m.dlc);
      std::copy_n(data, std::min<std::size_t>(size, f.len), f.data.begin());  // any bit pattern
      RIG_FUZZ_CHECK(db.decode(f).has_value());
    }
  });
  return 0;
}
