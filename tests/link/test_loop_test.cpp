// The loop test end to end over the real protocol code: LOOP_TEST and its burst through the
// codec, the firmware emulator driving the emulated DUT's physical loop, and CanDutLink
// collecting the burst, in lockstep under a SimClock. Faults: lost burst frames, a firmware
// without the command, the rig's switch off, a silent DUT, cancellation.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "firmware_link/can_dut_link.hpp"
#include "firmware_link/protocol.hpp"
#include "plant/emulated/dut_source.hpp"
#include "plant/firmware/inprocess_dut.hpp"
#include "rig/core/errors.hpp"
#include "test_support.hpp"

using namespace rig;
using namespace rig::link;

namespace {

// One emulated DUT (the real closed-loop model, default parameters) behind the CAN link.
struct LoopWorld {
  std::unique_ptr<plant::DutSource> src;
  SimClock clock;
  std::unique_ptr<InProcessDutLink> dut;
  explicit LoopWorld(InProcessDutOptions o = {}, uint64_t seed = 7) {
    src = plant::make_dut_source(nullptr, seed);
    dut = make_inprocess_dut(*src, clock, o);
    clock.set_advance([this](double dt) { dut->step(dt); });
  }
};

LoopTestRequest request(int steps = 2) {
  LoopTestRequest r;
  r.steps = steps;
  return r;
}

}  // namespace

TEST(LoopTestProtocol, BurstFramesRoundTripThroughTheCodec) {
  const LoopData d{513, Channel::Y, 42, -0.75f};
  const CanFrame f = encode(d);
  EXPECT_EQ(f.id, can_id::kLoopData);
  EXPECT_EQ(to_candump(f), "180#0102012A000040BF");
  const Decoded df = decode(f);
  const auto* back = std::get_if<LoopData>(&df.msg);
  ASSERT_NE(back, nullptr);
  EXPECT_EQ(back->index, 513);
  EXPECT_EQ(back->channel, Channel::Y);
  EXPECT_EQ(back->token, 42);
  EXPECT_EQ(back->value_g, -0.75f);

  const LoopEnd e{42, loop_cmd::kSaturated, 500, 50, 10000};
  const Decoded de = decode(encode(e));
  const auto* eb = std::get_if<LoopEnd>(&de.msg);
  ASSERT_NE(eb, nullptr);
  EXPECT_EQ(eb->token, 42);
  EXPECT_EQ(eb->status, loop_cmd::kSaturated);
  EXPECT_EQ(eb->samples, 500);
  EXPECT_EQ(eb->pre_samples, 50);
  EXPECT_EQ(eb->rate_hz, 10000);

  CanFrame bad = f;
  bad.data[2] = 7;  // no channel 7
  EXPECT_NE(decode(bad).error.find("channel 7"), std::string::npos);
  bad.len = 6;
  EXPECT_NE(decode(bad).error.find("length 6"), std::string::npos);
  EXPECT_STREQ(to_string(Op::LoopTest), "LOOP_TEST");
}

TEST(LoopTestLink, EmulatedDutAnswersWithItsLoopRecordedAtTheLoopRate) {
  LoopWorld w;
  const CancelToken never;
  const LoopTestResponse r = w.dut->loop_test(request(3), never);
  ASSERT_TRUE(r.supported) << r.reason;
  EXPECT_EQ(r.rate_hz, 10000.0);
  EXPECT_EQ(r.amplitude_g, 1.0);
  ASSERT_EQ(r.steps.size(), 3u);
  for (const LoopStepRecord& s : r.steps) {
    ASSERT_EQ(s.x.size(), 1000u);  // 100 ms at 10 kHz
    ASSERT_EQ(s.y.size(), 1000u);
    EXPECT_EQ(s.pre_samples, 100u);  // the step after a tenth of the record
    EXPECT_FALSE(s.saturated);
    // Before the step the loop holds the static input (a fraction of a mg); at the end it
    // balances the 1 g test torque on top of it, in x and through the filter in y.
    EXPECT_LT(std::abs(s.x[10]), 0.01);
    EXPECT_NEAR(s.x.back() - s.x[10], 1.0, 0.02);
    EXPECT_NEAR(s.y.back() - s.y[10], 1.0, 0.02);
    // The loop does not answer within one period: the torque reaches x through the pendulum.
    EXPECT_LT(std::abs(s.x[100] - s.x[99]), 0.01);
  }
  EXPECT_EQ(w.dut->firmware().stats().loop_tests, 3u);
  EXPECT_EQ(w.dut->client().malformed_frames(), 0u);
  // The DUT streams normally afterwards.
  w.dut->start_stream(never);
  std::vector<Sample> buf(100);
  EXPECT_EQ(w.dut->read(buf, never), 100u);
  EXPECT_LT(std::abs(buf.back().x_g), 0.01) << "the test torque is off again";
}

TEST(LoopTestLink, AFirmwareWithoutTheCommandIsNotSupportedNotAFault) {
  InProcessDutOptions o;
  o.firmware.loop_test = false;
  LoopWorld w(o);
  const LoopTestResponse r = w.dut->loop_test(request(), CancelToken{});
  EXPECT_FALSE(r.supported);
  EXPECT_NE(r.reason.find("UNKNOWN_OP"), std::string::npos) << r.reason;
  EXPECT_TRUE(r.steps.empty());
}

TEST(LoopTestLink, ASourceWithoutALoopModelHasNoLoopTest) {
  rig::link::testing::RampSource ramp;
  SimClock clock;
  auto dut = make_inprocess_dut(ramp, clock);
  clock.set_advance([&](double dt) { dut->step(dt); });
  EXPECT_FALSE(dut->loop_test(request(), CancelToken{}).supported);
}

TEST(LoopTestLink, SwitchedOffInTheHardwareFileTheRigDoesNotAsk) {
  InProcessDutOptions o;
  o.link.loop_test = false;
  LoopWorld w(o);
  const LoopTestResponse r = w.dut->loop_test(request(), CancelToken{});
  EXPECT_FALSE(r.supported);
  EXPECT_NE(r.reason.find("[dut] loop_test = false"), std::string::npos) << r.reason;
  EXPECT_EQ(w.dut->firmware().stats().commands, 0u) << "nothing was sent";
}

TEST(LoopTestLink, LostBurstFramesAreAHardwareErrorNamingTheFirstMissingSample) {
  LoopWorld w;
  plant::FirmwareFaults f;
  f.drop_burst_frames = {301};  // sample 150's y
  w.dut->firmware().set_faults(f);
  try {
    w.dut->loop_test(request(1), CancelToken{});
    FAIL() << "expected HardwareError";
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("1 of 1000 samples lost"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("index 150"), std::string::npos) << e.what();
  }
}

TEST(LoopTestLink, ALostEndMarkerIsATimeoutWithinItsBound) {
  LoopWorld w;
  plant::FirmwareFaults f;
  f.drop_burst_frames = {2000};  // the end marker of a 1000-sample burst
  w.dut->firmware().set_faults(f);
  const double t0 = w.clock.now_s();
  try {
    w.dut->loop_test(request(1), CancelToken{});
    FAIL() << "expected HardwareError";
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("no end of burst"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("2000 of 2000 frames"), std::string::npos) << e.what();
  }
  EXPECT_LT(w.clock.now_s() - t0, 2.0) << "bounded in device time";
}

TEST(LoopTestLink, RefusedWhileStreamingAndTheStreamIsRefusedDuringATest) {
  LoopWorld w;
  const CancelToken never;
  w.dut->start_stream(never);
  EXPECT_THROW(w.dut->loop_test(request(1), never), HardwareError);
  w.dut->stop_stream();
  // The firmware side: a START_STREAM while a test runs is BAD_STATE.
  w.dut->client().command({Op::LoopTest, 0, loop_cmd::kStep, 50, f32_bits(1.0f)}, never);
  EXPECT_THROW(w.dut->client().command({Op::StartStream, 0, 0, 0, 0}, never), HardwareError);
}

TEST(LoopTestLink, BadRequestsAreConfigErrors) {
  LoopWorld w;
  const CancelToken never;
  LoopTestRequest r;
  r.amplitude_g = 0;
  EXPECT_THROW(w.dut->loop_test(r, never), ConfigError);
  r.amplitude_g = 6;  // beyond half the range
  EXPECT_THROW(w.dut->loop_test(r, never), ConfigError);
  r.amplitude_g = 1;
  r.record_s = 0.5;
  EXPECT_THROW(w.dut->loop_test(r, never), ConfigError);
  // The firmware checks too: a record of 5 ms is a BAD_ARGUMENT.
  EXPECT_THROW(w.dut->client().command({Op::LoopTest, 0, loop_cmd::kStep, 5, f32_bits(1.0f)}, never), ConfigError);
}

TEST(LoopTestLink, CancellationEndsTheWait) {
  LoopWorld w;
  CancelSource cs;
  w.clock.set_advance([&](double dt) {
    w.dut->step(dt);
    if (w.clock.now_s() > 0.03) cs.request("operator");
  });
  EXPECT_THROW(w.dut->loop_test(request(1), cs.token()), AbortedError);
}

// ---- what the loop test measures, against the design model ----
#include "analysis/loop_response.hpp"
#include "plant/dut/loop_figures.hpp"
#include "design/filter.hpp"

// The emulated DUT's measured figures against the design model for the same parameters (the
// default DUT with the paper's W_f(z)): the model's value should lie inside the measured 95 %
// interval. Coverage is statistical, so over ten seeds at least eight must hold it (at a true
// 95 % coverage, 7 or fewer of 10 has a probability of 1.2 %); measured here: 10 of 10.
TEST(LoopTestFigures, EmulatedMeasurementAgreesWithTheModelWithinItsUncertainty) {
  const rig::design::LoopFigures model = rig::plant::loop_figures(nullptr, rig::design::paper_wf());
  int settling_inside = 0, bandwidth_inside = 0;
  for (uint64_t seed = 1; seed <= 10; ++seed) {
    LoopWorld w({}, seed);
    const LoopTestResponse r = w.dut->loop_test(request(5), CancelToken{});
    ASSERT_TRUE(r.supported);
    std::vector<double> ts, bw;
    for (const auto& s : r.steps) {
      const auto f = rig::analysis::step_figures(rig::analysis::unit_step(s.y, s.pre_samples, r.amplitude_g), r.rate_hz);
      ts.push_back(f.settling_time_s);
      bw.push_back(f.bandwidth_0p5_hz);
    }
    const auto T = rig::analysis::repeated_figure(ts, 1 / r.rate_hz);
    const auto B = rig::analysis::repeated_figure(bw, 1.0);
    settling_inside += T.lo <= model.settling_time_s && model.settling_time_s <= T.hi;
    bandwidth_inside += B.lo <= model.bandwidth_0p5_hz && model.bandwidth_0p5_hz <= B.hi;
    // And the intervals are narrow enough to mean something: a few percent.
    EXPECT_LT(T.hi - T.lo, 0.2 * T.value) << seed;
    EXPECT_LT(B.hi - B.lo, 0.02 * B.value) << seed;
  }
  EXPECT_GE(settling_inside, 8);
  EXPECT_GE(bandwidth_inside, 8);
}
