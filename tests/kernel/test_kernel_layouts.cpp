// Runs inside the guest kernel (guest/layouts.sh), after `rig run --hardware` recorded the
// emulated firmware streaming duts/qpa-counts.dbc on vcan0 and `rig capture import` turned
// candump's log of the same session into a capture: the live raw capture must be in the
// imported one, sample for sample (the same counters, bit-identical x and y), with 0 lost.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "rig/capture/capture.hpp"

namespace {

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

}  // namespace

TEST(KernelLayouts, CountsSessionLiveCaptureIsInTheImportedLogSampleForSample) {
  const std::string live_path = env("RIG_LIVE_CAPTURE"), imported_path = env("RIG_IMPORTED_CAPTURE");
  ASSERT_FALSE(live_path.empty() || imported_path.empty()) << "RIG_LIVE_CAPTURE and RIG_IMPORTED_CAPTURE";
  const auto live = rig::capture::load(live_path);
  const auto imported = rig::capture::load(imported_path);
  ASSERT_GE(live.samples.size(), 7000u) << "the raw phase's 8 s at 1 kHz";
  // 0 lost in the live recording: consecutive counters, no gap flag.
  for (std::size_t i = 1; i < live.samples.size(); ++i) {
    ASSERT_EQ(live.samples[i].seq, live.samples[i - 1].seq + 1) << "live sample " << i;
    ASSERT_EQ(live.samples[i].status & rig::sample_status::kGapBefore, 0u) << i;
  }
  // The live capture's counters are widened from the recording's first 16-bit counter, the
  // imported ones from the log's first frame: they agree modulo 2^16. Find the live start.
  const auto& L = live.samples;
  const auto& I = imported.samples;
  std::size_t j = I.size();
  for (std::size_t k = 0; k < I.size(); ++k)
    if ((I[k].seq & 0xFFFF) == (L[0].seq & 0xFFFF) && I[k].x_g == L[0].x_g && I[k].y_g == L[0].y_g) {
      j = k;
      break;
    }
  ASSERT_LT(j, I.size()) << "the live capture's first sample is not in the imported log";
  ASSERT_LE(j + L.size(), I.size()) << "the imported log ends inside the live recording";
  std::size_t same = 0;
  for (std::size_t i = 0; i < L.size(); ++i) {
    const rig::Sample& a = L[i];
    const rig::Sample& b = I[j + i];
    ASSERT_EQ(b.seq - I[j].seq, a.seq - L[0].seq) << "a sample missing from the log at live sample " << i;
    ASSERT_EQ(b.x_g, a.x_g) << i;
    ASSERT_EQ(b.y_g, a.y_g) << i;
    if (i > 0) {
      ASSERT_EQ(b.status & rig::sample_status::kGapBefore, 0u) << i;
    }
    ++same;
  }
  std::printf("live raw capture: %zu samples, all in the imported log from its sample %zu (of %zu)\n", same, j, I.size());
  // The run's log says the raw recording lost nothing either.
  const std::string runlog_path = env("RIG_RUN_LOG");
  if (!runlog_path.empty()) {
    std::ifstream in(runlog_path);
    std::stringstream ss;
    ss << in.rdbuf();
    EXPECT_EQ(ss.str().find("samples lost"), std::string::npos) << "run.log reports lost samples";
  }
}
