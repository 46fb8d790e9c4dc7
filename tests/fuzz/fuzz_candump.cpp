// Candump logs as technicians bring them (firmware_link/candump_log.hpp): every line is a
// frame, empty, or unreadable with a reason -- never an exception, never a silent drop.
// Invariants: a frame has at most 8 data bytes and an id that fits its format (11 or 29 bits),
// a finite time, and a data frame written back in cansend form (to_candump) reads back as the
// same frame; an unreadable line says why and carries its line number.
#include <cmath>
#include <sstream>
#include <string>

#include "firmware_link/candump_log.hpp"
#include "tests/fuzz/fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  std::istringstream in{std::string(rig::fuzz::as_text(data, size))};
  rig::link::CandumpLogReader reader(in);
  rig::link::CandumpLogReader::Entry e;
  std::size_t last_line = 0;
  while (reader.next(e)) {
    RIG_FUZZ_CHECK(e.line > last_line);
    last_line = e.line;
    if (e.parsed.kind == rig::link::LogLineKind::Unreadable) {
      RIG_FUZZ_CHECK(!e.parsed.problem.empty());
      continue;
    }
    RIG_FUZZ_CHECK(e.parsed.kind == rig::link::LogLineKind::Frame);
    const rig::link::LoggedFrame& lf = e.parsed.frame;
    const rig::link::CanFrame& f = lf.frame;
    RIG_FUZZ_CHECK(std::isfinite(lf.t_s));
    RIG_FUZZ_CHECK(f.len <= 8);
    if (!f.error) RIG_FUZZ_CHECK(f.id <= (f.extended ? 0x1FFFFFFFu : 0x7FFu));
    if (!f.rtr && !f.error) {
      const auto back = rig::link::read_candump_line(rig::link::to_candump(f));
      RIG_FUZZ_CHECK(back.kind == rig::link::LogLineKind::Frame);
      RIG_FUZZ_CHECK(back.frame.frame == f);
    }
  }
  return 0;
}
