// Capture files as they come off a disk: damaged, truncated, forged. The recovering reader
// either loads what it can, saying where the damage lies, or throws a ConfigError naming
// the file. Invariant: the samples delivered are the samples the recovery report counts.
#include <sys/mman.h>
#include <unistd.h>

#include <string>

#include "rig/capture/capture.hpp"
#include "tests/fuzz/fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  // An in-memory file with a path, so the reader runs exactly as on disk.
  static const int fd = memfd_create("fuzz-capture", 0);
  if (fd < 0 || ftruncate(fd, 0) != 0 || pwrite(fd, data, size, 0) != static_cast<ssize_t>(size)) return 0;
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  rig::fuzz::expect_only_rig_errors([&] {
    const rig::capture::Loaded l = rig::capture::load(path);
    RIG_FUZZ_CHECK(l.recovery.samples == l.samples.size());
    RIG_FUZZ_CHECK(!l.recovery.complete || (l.recovery.damaged_blocks == 0 && !l.recovery.truncated));
  });
  return 0;
}
