// Hardware files as technicians edit them, through the one validation every command uses
// (app/hardware_file.hpp: every section, every key) -- the file either passes, or the
// validation throws a ConfigError naming file:line:col. Invariant: a file that passes yields
// a [procedure] whose angles lie in their documented ranges once applied to a profile.
#include <sys/mman.h>
#include <unistd.h>

#include <cmath>
#include <string>

#include "app/hardware_file.hpp"
#include "tests/fuzz/fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  static const int fd = memfd_create("fuzz-hardware", 0);
  if (fd < 0 || ftruncate(fd, 0) != 0 || pwrite(fd, data, size, 0) != static_cast<ssize_t>(size)) return 0;
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  rig::fuzz::expect_only_rig_errors([&] {
    // No section required: partial files (rig table, rig dut) are validated the same way.
    const toml::table hw = rig::cli::load_hardware_file(path, {});
    rig::acceptance::Profile p;
    rig::cli::apply_procedure_angles(hw, p);
    RIG_FUZZ_CHECK(std::isfinite(p.u10_deg) && p.u10_deg >= -360 && p.u10_deg <= 360);
    RIG_FUZZ_CHECK(std::isfinite(p.u20_deg) && p.u20_deg >= -360 && p.u20_deg <= 540);
  });
  return 0;
}
