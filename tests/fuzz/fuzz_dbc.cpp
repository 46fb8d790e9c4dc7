// DBC text as a user or another tool writes it: the reader either returns a database or
// throws a ConfigError naming the line. Invariant: every signal of a parsed message fits
// in its message's payload.
#include <string>

#include "firmware_link/dbc.hpp"
#include "tests/fuzz/fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  rig::fuzz::expect_only_rig_errors([&] {
    const auto db = rig::link::Dbc::parse(std::string(rig::fuzz::as_text(data, size)), "fuzz.dbc");
    for (const auto& m : db.messages()) (void)db.find(m.id);
  });
  return 0;
}
