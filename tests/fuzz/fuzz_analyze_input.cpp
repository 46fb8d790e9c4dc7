// `rig analyze`'s readers as a user's files reach them (app/analyze_input.hpp): the first byte
// picks the reader -- text (one value per line), raw float64 mapped whole, raw float64 read in
// chunks with pread (the path of files too large to map), or one channel of a capture -- and
// the rest is the file. Each reader either returns values the analysis may use or throws a
// ConfigError naming the file and position. Invariant: every value delivered is finite and
// below analysis::kMaxMagnitude (what the Allan engine's accumulators are sized for), and a
// reader leaves no descriptor open behind it, refused files included.
#include <dirent.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "app/analyze_input.hpp"
#include "tests/fuzz/fuzz_target.hpp"

namespace {

void check_values(std::span<const double> v) {
  for (double x : v) RIG_FUZZ_CHECK(std::isfinite(x) && std::fabs(x) < rig::analysis::kMaxMagnitude);
}

// Reads a float64 file as the engine does: a sequential pass in small chunks, then re-reads
// from the start and from the middle (the engine's cursors), each value checked when first read.
// check_in_pass (a mapped file checked by the engine's pass, `rig analyze`): first the upper
// part of a split pass checks its range, as the engine's second thread does.
void read_f64(const std::string& path, std::size_t map_limit, bool check_in_pass = false) {
  const rig::cli::F64File f(path, map_limit, check_in_pass);
  if (check_in_pass) {
    f.will_read(f.size() / 2, f.size() - f.size() / 2);
    f.check_range(f.size() / 2, f.size() - f.size() / 2);
  }
  std::vector<double> buf(3);
  for (int pass = 0; pass < 2; ++pass)
    for (std::uint64_t pos = pass == 0 ? 0 : f.size() / 2; pos < f.size();) {
      const std::size_t got = f.read_at(pos, buf);
      RIG_FUZZ_CHECK(got > 0 && got <= buf.size());
      check_values(std::span<const double>(buf.data(), got));
      pos += got;
    }
  RIG_FUZZ_CHECK(f.read_at(f.size(), buf) == 0);
}

// Descriptors open on the harness's in-memory file other than its own: what a reader leaked
// (regressions/analyze_input). Only the file's own descriptors are counted: libFuzzer's and
// the sanitizers' threads open files of their own at any time.
int leaked_descriptors(int own) {
  int n = 0;
  DIR* dir = ::opendir("/proc/self/fd");
  if (!dir) return 0;
  while (const dirent* e = ::readdir(dir)) {
    if (e->d_name[0] == '.' || std::atoi(e->d_name) == own) continue;
    char link[256];
    const std::string at = std::string("/proc/self/fd/") + e->d_name;
    const ssize_t k = ::readlink(at.c_str(), link, sizeof link - 1);
    if (k > 0 && std::string_view(link, static_cast<std::size_t>(k)).find("fuzz-analyze-input") != std::string_view::npos) ++n;
  }
  ::closedir(dir);
  return n;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const int fd = memfd_create("fuzz-analyze-input", 0);

  if (fd < 0 || ftruncate(fd, 0) != 0 || pwrite(fd, data + 1, size - 1, 0) != static_cast<ssize_t>(size - 1)) return 0;
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  rig::fuzz::expect_only_rig_errors([&] {
    switch (data[0] % 4) {
      case 0: check_values(rig::cli::read_text(path)); break;
      case 1: read_f64(path, std::size_t(1) << 30, data[0] & 4); break;  // mapped: checked at open, or in the pass
      case 2: read_f64(path, 0); break;                      // pread, checked as first read
      case 3: check_values(rig::cli::read_capture(path, data[0] & 4 ? "y" : "x").values); break;
    }
  });
  RIG_FUZZ_CHECK(leaked_descriptors(fd) == 0);
  return 0;
}
