// Writes a small capture with known content (for the NumPy loader test).
#include <cstdio>
#include <string_view>

#include "rig/capture/capture.hpp"

int main(int argc, char** argv) {
  // `--help` (or any option) is not a file to write: a capture named "--help" was left in a
  // working copy and committed once.
  if (argc != 2 || argv[1][0] == '-') {
    std::fprintf(stderr, "usage: make_test_capture OUT.cap\n");
    return argc == 2 && std::string_view(argv[1]) == "--help" ? 0 : 2;
  }
  rig::capture::Header h;
  h.serial = "PY-1";
  h.phase = "raw";
  h.orientation = "U20";
  h.rate_hz = 1000;
  rig::capture::Writer w(argv[1], h, 1000);
  for (uint32_t i = 0; i < 2500; ++i) {
    const rig::Sample s{i, static_cast<float>(i) * 0.5f, -static_cast<float>(i) * 0.25f, i & 1u};
    w.append(std::span(&s, 1));
  }
  w.close();
  return 0;
}
