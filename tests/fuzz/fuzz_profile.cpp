// Profile files as technicians edit them: the loader either returns a profile whose values
// the procedure can run with, or throws a ConfigError naming file:line:column.
// Invariants: a loaded profile has a positive rate, at least one run pair, and positive
// durations (what the procedure divides by and loops over), and a tau grid the allan phase
// can use (a bad one used to surface only after the whole recording, issue 13).
#include <sys/mman.h>
#include <unistd.h>

#include <stdexcept>
#include <string>

#include "analysis/allan.hpp"
#include "procedures/acceptance/profile.hpp"
#include "tests/fuzz/fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  static const int fd = memfd_create("fuzz-profile", 0);
  if (fd < 0 || ftruncate(fd, 0) != 0 || pwrite(fd, data, size, 0) != static_cast<ssize_t>(size)) return 0;
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  rig::fuzz::expect_only_rig_errors([&] {
    const rig::acceptance::Profile p = rig::acceptance::load_profile(path);
    RIG_FUZZ_CHECK(p.rate_hz > 0);
    RIG_FUZZ_CHECK(!p.order.empty());
    RIG_FUZZ_CHECK(p.run_s > 0 && p.in_run_s > 0 && p.raw_s > 0);
    bool taus_usable = true;
    try {
      rig::analysis::parse_tau_grid(p.taus);
    } catch (const std::invalid_argument&) {
      taus_usable = false;
    }
    RIG_FUZZ_CHECK(taus_usable);
  });
  return 0;
}
