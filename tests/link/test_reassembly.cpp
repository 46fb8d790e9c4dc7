#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "firmware_link/reassembly.hpp"
#include "rig/core/errors.hpp"

using namespace rig::link;
using rig::Sample;
namespace ss = rig::sample_status;

namespace {

void push_sample(StreamReassembler& r, uint32_t seq, float v = 0, uint8_t status = 0) {
  r.push({Channel::X, seq & kSeqMask, status, v});
  r.push({Channel::Y, seq & kSeqMask, status, -v});
}

std::vector<Sample> drain(StreamReassembler& r) {
  std::vector<Sample> out(r.ready());
  r.pop(out);
  return out;
}

}  // namespace

TEST(Reassembly, InOrderSamplesAreDeliveredAtOnce) {
  StreamReassembler r;
  for (uint32_t s = 100; s < 110; ++s) push_sample(r, s, static_cast<float>(s));
  const auto out = drain(r);
  ASSERT_EQ(out.size(), 10u);
  for (std::size_t i = 0; i < out.size(); ++i) {
    EXPECT_EQ(out[i].seq, 100 + i);
    EXPECT_EQ(out[i].x_g, static_cast<float>(100 + i));
    EXPECT_EQ(out[i].y_g, -static_cast<float>(100 + i));
    EXPECT_EQ(out[i].status & ss::kGapBefore, 0u);
  }
  EXPECT_EQ(r.stats().received, 10u);
  EXPECT_EQ(r.stats().gaps, 0u);
}

TEST(Reassembly, GapsAreCountedLocatedAndFlagged) {
  StreamReassembler r(4);
  for (uint32_t s = 0; s < 10; ++s) push_sample(r, s);
  for (uint32_t s = 13; s < 30; ++s) push_sample(r, s);  // 10,11,12 lost
  for (uint32_t s = 31; s < 50; ++s) push_sample(r, s);  // 30 lost
  const auto out = drain(r);
  ASSERT_EQ(out.size(), 46u);
  EXPECT_EQ(r.stats().gaps, 2u);
  EXPECT_EQ(r.stats().lost, 4u);
  ASSERT_EQ(r.stats().gap_list.size(), 2u);
  EXPECT_EQ(r.stats().gap_list[0], (std::pair<uint64_t, uint64_t>{10, 3}));
  EXPECT_EQ(r.stats().gap_list[1], (std::pair<uint64_t, uint64_t>{30, 1}));
  for (const auto& s : out) EXPECT_EQ((s.status & ss::kGapBefore) != 0, s.seq == 13 || s.seq == 31) << s.seq;
}

TEST(Reassembly, HalfSampleIsLostNotInvented) {
  StreamReassembler r(2);
  push_sample(r, 0);
  r.push({Channel::X, 1, 0, 1.0f});  // Y of sample 1 never comes
  for (uint32_t s = 2; s < 6; ++s) push_sample(r, s);
  const auto out = drain(r);
  ASSERT_EQ(out.size(), 5u);
  EXPECT_EQ(out[1].seq, 2u);
  EXPECT_TRUE(out[1].status & ss::kGapBefore);
  EXPECT_EQ(r.stats().lost, 1u);
  EXPECT_EQ(r.orphan_halves(), 1u);
}

TEST(Reassembly, DuplicatesAndLateFramesAreDroppedAndCounted) {
  StreamReassembler r(2);
  push_sample(r, 0, 1.0f);
  push_sample(r, 0, 9.0f);  // duplicate of a delivered sample: both halves late
  push_sample(r, 1, 2.0f);
  r.push({Channel::X, 2, 0, 3.0f});
  r.push({Channel::X, 2, 0, 7.0f});  // duplicate half while pending
  r.push({Channel::Y, 2, 0, -3.0f});
  for (uint32_t s = 4; s < 8; ++s) push_sample(r, s);  // 3 given up after the window...
  push_sample(r, 3, 5.0f);                              // ...so it is late when it arrives
  const auto out = drain(r);
  ASSERT_EQ(out.size(), 7u);
  EXPECT_EQ(out[0].x_g, 1.0f);
  EXPECT_EQ(out[2].x_g, 3.0f);  // first copy wins
  EXPECT_EQ(r.stats().duplicates, 2u + 1u + 2u);
  EXPECT_EQ(r.stats().lost, 1u);
  EXPECT_EQ(r.stats().gap_list.at(0).first, 3u);
}

TEST(Reassembly, ReorderWithinWindowIsRepaired) {
  StreamReassembler r(8);
  // A controller swapped mailboxes: X(1), X(2) overtake Y(0)... all within the window.
  r.push({Channel::X, 0, 0, 0.f});
  r.push({Channel::X, 1, 0, 1.f});
  r.push({Channel::X, 2, 0, 2.f});
  r.push({Channel::Y, 0, 0, -0.f});
  r.push({Channel::Y, 2, 0, -2.f});
  r.push({Channel::Y, 1, 0, -1.f});
  const auto out = drain(r);
  ASSERT_EQ(out.size(), 3u);
  for (uint32_t i = 0; i < 3; ++i) EXPECT_EQ(out[i].seq, i);
  EXPECT_EQ(r.stats().gaps, 0u);
  EXPECT_EQ(r.stats().duplicates, 0u);
}

TEST(Reassembly, Wire24BitCounterWrapsIntoAWiderSequence) {
  StreamReassembler r(4);
  const uint32_t start = kSeqMask - 5;
  for (uint32_t i = 0; i < 12; ++i) push_sample(r, start + i);  // crosses 0xFFFFFF -> 0x000000
  push_sample(r, start + 14);                                    // 2 lost right after the wrap
  for (uint32_t i = 15; i < 20; ++i) push_sample(r, start + i);
  const auto out = drain(r);
  ASSERT_EQ(out.size(), 18u);
  EXPECT_EQ(out[5].seq, kSeqMask);
  EXPECT_EQ(out[6].seq, kSeqMask + 1);  // widened, not back to 0
  EXPECT_EQ(out[12].seq, start + 14);
  EXPECT_TRUE(out[12].status & ss::kGapBefore);
  ASSERT_EQ(r.stats().gap_list.size(), 1u);
  EXPECT_EQ(r.stats().gap_list[0], (std::pair<uint64_t, uint64_t>{start + 12ull, 2}));
}

TEST(Reassembly, LongOutageIsOneGapAccountedInOneStep) {
  StreamReassembler r(8);
  push_sample(r, 10);
  push_sample(r, 10 + 4000000);  // ~67 min of silence, still within +-2^23
  for (uint32_t i = 1; i < 9; ++i) push_sample(r, 10 + 4000000 + i);
  const auto out = drain(r);
  ASSERT_EQ(out.size(), 10u);
  EXPECT_EQ(r.stats().lost, 3999999u);
  EXPECT_EQ(r.stats().gaps, 1u);
}

TEST(Reassembly, GapListIsBoundedButCountsAreNot) {
  StreamReassembler r(1);
  for (uint32_t s = 0; s < 2 * 1500; s += 2) push_sample(r, s);  // every other sample lost
  drain(r);
  EXPECT_EQ(r.stats().gaps, 1499u);
  EXPECT_EQ(r.stats().lost, 1499u);
  EXPECT_EQ(r.stats().gap_list.size(), StreamReassembler::kMaxGapList);
}

TEST(Reassembly, FlushSettlesMiddleButDropsTheCutOffTail) {
  StreamReassembler r(8);
  push_sample(r, 0);
  push_sample(r, 2);                  // 1 missing, 2 complete but waiting within the window
  r.push({Channel::X, 3, 0, 0.f});    // tail half
  EXPECT_EQ(r.ready(), 1u);
  r.flush();
  const auto out = drain(r);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1].seq, 2u);
  EXPECT_EQ(r.stats().lost, 1u);
  r.restart();
  push_sample(r, 500);  // a new stream starts wherever the DUT's counter is
  EXPECT_EQ(drain(r).at(0).seq, 500u);
  EXPECT_EQ(r.stats().gaps, 1u);
}

TEST(Reassembly, StatusBitsPassThrough) {
  StreamReassembler r;
  push_sample(r, 0, 0.f, 0x05);
  EXPECT_EQ(drain(r).at(0).status, 0x05u);
}

// ---- counters of other widths (DBC-described streams) ------------------------------------

namespace {
void push_n(StreamReassembler& r, uint32_t counter, int bits, float v = 0) {
  const uint32_t mask = (uint32_t{1} << bits) - 1;
  r.push_part({Channel::X, counter & mask, uint8_t{0}, v});
  r.push_part({Channel::Y, counter & mask, uint8_t{0}, -v});
}
}  // namespace

TEST(Reassembly, SixteenBitCounterWrapsGapsAndLateFramesAsTwentyFour) {
  // The same sequence as Wire24BitCounterWrapsIntoAWiderSequence, on a 16-bit counter.
  StreamReassembler r(4, 16);
  const uint32_t start = 0xFFFF - 5;
  for (uint32_t i = 0; i < 12; ++i) push_n(r, start + i, 16);
  push_n(r, start + 14, 16);
  for (uint32_t i = 15; i < 20; ++i) push_n(r, start + i, 16);
  push_n(r, start + 3, 16);  // a late frame from before the wrap: a duplicate, not a new sample
  const auto out = drain(r);
  ASSERT_EQ(out.size(), 18u);
  EXPECT_EQ(out[5].seq, 0xFFFFu);
  EXPECT_EQ(out[6].seq, 0x10000u);
  EXPECT_TRUE(out[12].status & ss::kGapBefore);
  EXPECT_EQ(r.stats().gap_list.at(0), (std::pair<uint64_t, uint64_t>{start + 12ull, 2}));
  EXPECT_EQ(r.stats().duplicates, 2u);
  // An outage within half the period is one gap; the widening is relative to the highest seen.
  push_n(r, start + 20 + 30000, 16);
  for (uint32_t i = 1; i < 6; ++i) push_n(r, start + 20 + 30000 + i, 16);
  EXPECT_EQ(drain(r).back().seq, start + 20 + 30005);
  EXPECT_EQ(r.stats().lost, 2u + 30000u);
}

TEST(Reassembly, StatusOnlyWhereAFrameCarriesIt) {
  StreamReassembler r(8, 16);
  r.push_part({Channel::X, 1, uint8_t{stream_status::kSaturated}, 1.0f});
  r.push_part({Channel::Y, 1, std::nullopt, 2.0f});  // y's frame has no status: x's stands
  const auto out = drain(r);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].status, stream_status::kSaturated);
}

TEST(Reassembly, WithoutYASampleIsCompleteWithX) {
  StreamReassembler r(8, 12, false);
  for (uint32_t k = 4090; k < 4100; ++k) r.push_part({Channel::X, k & 0xFFF, std::nullopt, 1.0f});
  const auto out = drain(r);
  ASSERT_EQ(out.size(), 10u);
  EXPECT_EQ(out.back().seq, 4099u);
  EXPECT_TRUE(std::isnan(out[0].y_g));
}

TEST(Reassembly, CounterWidthAndWindowAreChecked) {
  EXPECT_THROW(StreamReassembler(8, 1), rig::ConfigError);
  EXPECT_THROW(StreamReassembler(8, 33), rig::ConfigError);
  EXPECT_THROW(StreamReassembler(200, 8), rig::ConfigError);  // the window would span the wrap
  EXPECT_NO_THROW(StreamReassembler(128, 8));
  EXPECT_NO_THROW(StreamReassembler(8, 32));
}

// A log's import holds the start for the reorder window: the first sample logged a few frames
// late takes its place (it counted as a duplicate). A live link does not hold (the default).
TEST(Reassembly, AHeldStartTakesTheFirstSampleLoggedLate) {
  for (const bool hold : {false, true}) {
    StreamReassembler r(4, 24, true, hold);
    push_sample(r, 11);
    push_sample(r, 12);
    EXPECT_EQ(r.ready(), hold ? 0u : 2u);
    push_sample(r, 10);
    for (uint32_t s = 13; s < 20; ++s) push_sample(r, s);
    r.flush();
    const auto out = drain(r);
    ASSERT_EQ(out.size(), hold ? 10u : 9u);
    EXPECT_EQ(out.front().seq, hold ? 10u : 11u);
    EXPECT_EQ(r.stats().duplicates, hold ? 0u : 2u);
    EXPECT_EQ(r.stats().gaps, 0u);
  }
  // Further back than the window: the start does not move.
  StreamReassembler r(4, 24, true, true);
  for (uint32_t s = 20; s < 24; ++s) push_sample(r, s);
  push_sample(r, 15);
  r.flush();
  EXPECT_EQ(drain(r).front().seq, 20u);
  EXPECT_EQ(r.stats().duplicates, 2u);
}

// Near the 24-bit wrap a late frame of the sample before the start widens below 0: it is late,
// never sample 0 (it was clamped to 0 and, with the start held, took sample 0's place).
TEST(Reassembly, AFrameBeforeTheStartAcrossTheWrapIsLateNotSampleZero) {
  StreamReassembler r(8, 24, true, true);
  push_sample(r, 1, 1.0f);
  push_sample(r, 2, 2.0f);
  push_sample(r, 0xFFFFFF, 99.0f);
  push_sample(r, 0, 0.5f);
  for (uint32_t s = 3; s < 20; ++s) push_sample(r, s, static_cast<float>(s));
  r.flush();
  const auto out = drain(r);
  ASSERT_EQ(out.size(), 20u);
  EXPECT_EQ(out.front().seq, 0u);
  EXPECT_EQ(out.front().x_g, 0.5f);
  EXPECT_EQ(r.stats().duplicates, 2u);
  EXPECT_EQ(r.stats().gaps, 0u);
}
