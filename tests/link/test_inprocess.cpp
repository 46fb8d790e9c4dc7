// The in-process bus, the DUT firmware emulator and the rig's CanDutLink
// together, in lockstep under a SimClock: the real protocol code end to end,
// with no wall-clock sleeping.
#include <gtest/gtest.h>

#include <vector>

#include "firmware_link/can_dut_link.hpp"
#include "firmware_link/inprocess_bus.hpp"
#include "plant/firmware/firmware_emulator.hpp"
#include "plant/firmware/inprocess_dut.hpp"
#include "rig/core/errors.hpp"
#include "test_support.hpp"

#include <linux/can/error.h>

using namespace rig;
using namespace rig::link;
using rig::link::testing::RampSource;

namespace {

// A world of one DUT: the SimClock's advance steps the firmware.
struct World {
  RampSource src;
  SimClock clock;
  std::unique_ptr<InProcessDutLink> dut;
  explicit World(InProcessDutOptions o = {}) {
    dut = make_inprocess_dut(src, clock, o);
    clock.set_advance([this](double dt) { dut->step(dt); });
  }
};

std::vector<Sample> read_n(DutLink& l, std::size_t n, const CancelToken& c = {}) {
  std::vector<Sample> v(n);
  EXPECT_EQ(l.read(v, c), n);
  return v;
}

}  // namespace

// ---- the bus itself ----

// The port's receive queue: first in, first out through drains, refills and the compaction of
// a queue that is never drained (more than 4096 frames read, at least half of its storage).
TEST(FrameFifo, KeepsOrderThroughDrainsAndCompaction) {
  FrameFifo q;
  uint32_t pushed = 0, popped = 0;
  auto push = [&](int n) {
    for (int i = 0; i < n; ++i) {
      RxFrame f;
      f.frame.id = pushed++;
      q.push_back(f);
    }
  };
  auto pop = [&](int n) {
    for (int i = 0; i < n; ++i) {
      ASSERT_FALSE(q.empty());
      ASSERT_EQ(q.front().frame.id, popped++);
      q.pop_front();
    }
  };
  push(3);
  pop(3);  // drained: starts over
  EXPECT_TRUE(q.empty());
  for (int round = 0; round < 6; ++round) {  // never drained: the read part is dropped on the way
    push(5000);
    pop(4000);
    EXPECT_EQ(q.size(), pushed - popped);
  }
  pop(static_cast<int>(pushed - popped));
  EXPECT_TRUE(q.empty());
  EXPECT_EQ(q.size(), 0u);
}

TEST(InProcessBus, DeliversToOtherPortsOnlyThroughFilters) {
  auto bus = InProcessBus::create();
  auto a = bus->open("a"), b = bus->open("b"), c = bus->open("c");
  const CanFilter only_100[] = {{0x100, 0x7FF}};
  c->set_filters(only_100);
  CanFrame f;
  f.id = 0x123;
  f.len = 1;
  a->send(f);
  f.id = 0x100;
  a->send(f);
  const CancelToken never;
  EXPECT_FALSE(a->receive(0, never));  // no echo to the sender
  EXPECT_EQ(b->receive(0, never)->frame.id, 0x123u);
  EXPECT_EQ(b->receive(0, never)->frame.id, 0x100u);
  EXPECT_EQ(c->receive(0, never)->frame.id, 0x100u);
  EXPECT_FALSE(c->receive(0, never));
  EXPECT_EQ(a->stats().tx, 2u);
  EXPECT_EQ(b->stats().rx, 2u);
}

TEST(InProcessBus, FullQueueDropsAndCounts) {
  InProcessBus::Options o;
  o.rx_capacity = 3;
  auto bus = InProcessBus::create(o);
  auto a = bus->open("a"), b = bus->open("b");
  for (int i = 0; i < 5; ++i) a->send(CanFrame{});
  EXPECT_EQ(b->stats().rx_dropped, 2u);
}

namespace {

// SocketCAN error frames (linux/can/error.h): a controller's warning, and a bus-off.
CanFrame rx_warning_frame() {
  CanFrame f;
  f.error = true;
  f.id = CAN_ERR_CRTL;
  f.len = 8;
  f.data[1] = CAN_ERR_CRTL_RX_WARNING;
  return f;
}

CanFrame bus_off_frame() {
  CanFrame f;
  f.error = true;
  f.id = CAN_ERR_BUSOFF;
  f.len = 8;
  return f;
}

}  // namespace

TEST(InProcessBus, BusOffAndErrorPassiveAreLinkFaultsWarningsAreNot) {
  auto bus = InProcessBus::create();
  auto rx = bus->open("rig");
  const CanFrame warn = rx_warning_frame();
  bus->inject(warn);
  CanFrame ok;
  ok.id = 0x5;
  bus->inject(ok);
  EXPECT_EQ(rx->receive(0, {})->frame.id, 0x5u);  // the warning was skipped
  EXPECT_EQ(rx->stats().error_frames, 1u);

  CanFrame passive = warn;
  passive.data[1] = CAN_ERR_CRTL_TX_PASSIVE;
  bus->inject(passive);
  try {
    rx->receive(0, {});
    FAIL();
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("error passive (tx)"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("inprocess:bus0/rig"), std::string::npos) << e.what();
  }
  const CanFrame busoff = bus_off_frame();
  bus->inject(busoff);
  EXPECT_THROW(rx->receive(0, {}), HardwareError);
  EXPECT_TRUE(classify_error_frame(busoff).fatal);
  EXPECT_EQ(classify_error_frame(busoff).text, "bus-off");
}

TEST(InProcessBus, ReceiveHonoursCancellation) {
  auto bus = InProcessBus::create();
  auto rx = bus->open("rig");
  CancelSource src;
  src.request("test");
  EXPECT_THROW(rx->receive(1.0, src.token()), AbortedError);
}

// In lockstep the bus owns simulated time: a receive that finds nothing queued steps the
// SimClock by its timeout (the world sends meanwhile), one that finds a frame does not, and
// frames carry the clock's time -- so the client never needs to know time is simulated.
TEST(InProcessBus, LockstepReceiveStepsTheSimClockOnlyWhenNothingIsQueued) {
  SimClock clock;
  InProcessBus::Options o;
  o.lockstep = &clock;
  auto bus = InProcessBus::create(o);
  auto world = bus->open("world"), rig = bus->open("rig");
  CanFrame f;
  f.id = 0x100;
  f.len = 1;
  clock.set_advance([&](double) {
    if (clock.now_s() >= 0.02 - 1e-9 && world->stats().tx == 0) world->send(f);  // sent in the slice from 20 ms
  });
  const CancelToken never;
  EXPECT_FALSE(rig->receive(0, never));  // a poll: time does not move
  EXPECT_EQ(clock.now_s(), 0.0);
  const auto rx = rig->receive(0.05, never);
  ASSERT_TRUE(rx);
  EXPECT_NEAR(clock.now_s(), 0.05, 1e-12);  // the whole timeout was simulated
  EXPECT_NEAR(rx->t_s, 0.02, 1e-9);         // stamped when the world sent it
  EXPECT_DOUBLE_EQ(rig->now_s(), clock.now_s());
  world->send(f);
  EXPECT_TRUE(rig->receive(1.0, never));  // queued: returned at once
  EXPECT_NEAR(clock.now_s(), 0.05, 1e-12);
}

// The batch calls (issue 17) must mean exactly what their frame-by-frame loops mean.
TEST(InProcessBus, BatchesKeepOrderFiltersAndCountsOfSingleFrames) {
  SimClock clock;
  InProcessBus::Options o;
  o.lockstep = &clock;
  auto bus = InProcessBus::create(o);
  auto a = bus->open("a"), b = bus->open("b"), c = bus->open("c");
  const CanFilter odd_only[] = {{0x101, 0x7FF}, {0x103, 0x7FF}};
  c->set_filters(odd_only);
  std::vector<CanFrame> frames(5);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    frames[i].id = 0x100 + static_cast<uint32_t>(i);
    frames[i].len = 1;
  }
  frames[4].len = 9;  // a bad frame: the ones before it go out, then the error
  EXPECT_THROW(a->send_batch(frames), HardwareError);
  EXPECT_EQ(a->stats().tx, 4u);
  const CancelToken never;
  std::vector<RxFrame> got;
  EXPECT_EQ(b->receive_batch(got, 3, 0, never), 3u);  // at most `max`
  EXPECT_EQ(b->receive_batch(got, 100, 0, never), 1u);
  ASSERT_EQ(got.size(), 4u);
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i].frame.id, 0x100u + i);
  EXPECT_EQ(b->stats().rx, 4u);
  got.clear();
  EXPECT_EQ(c->receive_batch(got, 100, 0, never), 2u);  // through its filters
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].frame.id, 0x101u);
  EXPECT_EQ(got[1].frame.id, 0x103u);
  // Nothing queued: a poll leaves time alone; a timeout steps the world once, as receive() does.
  int advances = 0;
  clock.set_advance([&](double) {
    if (++advances == 1) a->send_batch(std::span(frames).first(2));
  });
  got.clear();
  EXPECT_EQ(b->receive_batch(got, 100, 0, never), 0u);
  EXPECT_EQ(advances, 0);
  EXPECT_EQ(b->receive_batch(got, 100, 0.01, never), 2u);
  EXPECT_NEAR(clock.now_s(), 0.01, 1e-12);
  EXPECT_EQ(got[0].t_s, got[1].t_s);  // one batch, one timestamp
  EXPECT_FALSE(b->receive(0, never));
}

// A batch reads error frames as receive() does: a warning is counted and skipped, a bus-off
// ends the batch with the link fault (the frames before it taken, the ones after it kept).
TEST(InProcessBus, ABatchSkipsErrorWarningsAndStopsAtABusOff) {
  SimClock clock;
  InProcessBus::Options o;
  o.lockstep = &clock;
  auto bus = InProcessBus::create(o);
  auto rx = bus->open("rig");
  const CanFrame warn = rx_warning_frame(), busoff = bus_off_frame();
  CanFrame f;
  f.len = 1;
  for (uint32_t id : {0x1u, 0x2u}) f.id = id, bus->inject(f);
  bus->inject(warn);
  f.id = 0x3;
  bus->inject(f);
  bus->inject(busoff);
  f.id = 0x4;
  bus->inject(f);
  const CancelToken never;
  std::vector<RxFrame> got;
  EXPECT_EQ(rx->receive_batch(got, 2, 0, never), 2u);
  EXPECT_THROW(rx->receive_batch(got, 100, 0, never), HardwareError);
  ASSERT_EQ(got.size(), 3u);  // 0x3 was taken before the bus-off
  EXPECT_EQ(got[2].frame.id, 0x3u);
  EXPECT_EQ(rx->stats().error_frames, 2u);
  EXPECT_EQ(rx->stats().rx, 3u);
  got.clear();
  EXPECT_EQ(rx->receive_batch(got, 100, 0, never), 1u);  // the frame after it is still queued
  EXPECT_EQ(got[0].frame.id, 0x4u);
  EXPECT_FALSE(rx->receive(0, never));
}

// ---- firmware + client, lockstep ----

TEST(InProcessDut, InfoRoundTrips) {
  World w;
  w.src.serial_ = "QPA-2026-000117";  // 15 characters: 4 chunks
  const DutInfo i = w.dut->info({});
  EXPECT_EQ(i.serial, "QPA-2026-000117");
  EXPECT_EQ(i.firmware, "1.4.0");
  EXPECT_FLOAT_EQ(static_cast<float>(i.temperature_c), 23.25f);
  EXPECT_EQ(i.output_rate_hz, 1000.0);
  EXPECT_GT(w.clock.now_s(), 0.0);  // the commands took simulated time...
  EXPECT_LT(w.clock.now_s(), 0.05);  // ...about one tick each
}

TEST(InProcessDut, StreamDeliversEverySampleInOrderWithExactValues) {
  World w;
  w.clock.sleep_for(0.25, {});  // the DUT ran before the rig started listening
  w.dut->start_stream({});
  const auto v = read_n(*w.dut, 20000);
  w.dut->stop_stream();
  const uint32_t first = v.front().seq;
  EXPECT_GE(first, 250u);
  for (std::size_t i = 0; i < v.size(); ++i) {
    ASSERT_EQ(v[i].seq, first + i);
    ASSERT_EQ(v[i].x_g, RampSource::x_of(v[i].seq));
    ASSERT_EQ(v[i].y_g, RampSource::y_of(v[i].seq));
    ASSERT_EQ(v[i].status, sample_status::kFilterOn);
  }
  const LinkStats s = w.dut->stats();
  EXPECT_EQ(s.received, 20000u);
  EXPECT_EQ(s.gaps, 0u);
  EXPECT_EQ(s.duplicates, 0u);
  // Lockstep: 20 000 samples cost about 20 s of simulated time, not more.
  EXPECT_NEAR(w.clock.now_s(), 0.25 + 20.0, 0.2);
}

TEST(InProcessDut, DroppedSamplesAndFramesAreDetectedAndLocated) {
  World w;
  w.dut->start_stream({});
  const uint64_t base = w.dut->firmware().sample_counter();
  plant::FirmwareFaults f;
  f.drop_samples = {{base + 100, 5}, {base + 1000, 1}};
  f.drop_frames = {{base + 2000, 1}};  // only the Y half of one sample
  f.duplicate_samples = {base + 3000};
  w.dut->firmware().set_faults(f);
  const auto v = read_n(*w.dut, 5000);
  const LinkStats s = w.dut->stats();
  EXPECT_EQ(s.gaps, 3u);
  EXPECT_EQ(s.lost, 7u);
  ASSERT_EQ(s.gap_list.size(), 3u);
  EXPECT_EQ(s.gap_list[0], (std::pair<uint64_t, uint64_t>{base + 100, 5}));
  EXPECT_EQ(s.gap_list[1], (std::pair<uint64_t, uint64_t>{base + 1000, 1}));
  EXPECT_EQ(s.gap_list[2], (std::pair<uint64_t, uint64_t>{base + 2000, 1}));
  EXPECT_EQ(s.duplicates, 2u);  // both halves of the repeated sample
  int flagged = 0;
  for (const auto& x : v)
    if (x.status & sample_status::kGapBefore) {
      ++flagged;
      EXPECT_TRUE(x.seq == base + 105 || x.seq == base + 1001 || x.seq == base + 2001) << x.seq;
    }
  EXPECT_EQ(flagged, 3);
  EXPECT_EQ(w.dut->firmware().stats().samples_dropped, 6u);
  w.dut->reset_stats();
  EXPECT_EQ(w.dut->stats().gaps, 0u);
}

TEST(InProcessDut, SilenceIsAHardwareFaultWithin100ms) {
  World w;
  w.dut->start_stream({});
  read_n(*w.dut, 100);
  plant::FirmwareFaults f;
  f.silent_from = w.dut->firmware().sample_counter() + 50;
  w.dut->firmware().set_faults(f);
  std::vector<Sample> v(1000);
  try {
    w.dut->read(v, {});
    FAIL() << "expected HardwareError";
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("silent"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("inprocess:dut-bus/rig"), std::string::npos) << e.what();
  }
  // Sample k is produced at (k + 1) ms of simulated time; the last one before
  // the silence was silent_from - 1. Frames carry the SimClock's time at the
  // start of its 10 ms slice, so silence is declared 90..101 ms after it.
  const double last_sample_t = static_cast<double>(*f.silent_from) * 1e-3;
  EXPECT_GE(w.clock.now_s() - last_sample_t, 0.09 - 1e-9);
  EXPECT_LE(w.clock.now_s() - last_sample_t, 0.1 + 0.002);
}

TEST(InProcessDut, ASilentDutFailsCommandsAfterRetries) {
  World w;
  plant::FirmwareFaults f;
  f.silent_from = 0;
  w.dut->firmware().set_faults(f);
  try {
    w.dut->info({});
    FAIL();
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("GET_SERIAL (op 0x30)"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("3 attempts"), std::string::npos) << e.what();
  }
  EXPECT_NEAR(w.clock.now_s(), 3 * 0.25, 0.01);
}

TEST(InProcessDut, FilterSetGetEnableRoundTrip) {
  World w;
  FilterConfig f;  // the paper's MCU filter (docs/method.md): 0.148895 z^2 / (z^2 - 1.228261 z + 0.377156)
  f.sections = {{0.148895, 0, 0, -1.228261, 0.377156}, {0.5, 0.25, 0.125, 0.1, 0.05}};
  f.rate_hz = 10000;
  f.enabled = false;
  w.dut->set_filter(f, {});
  // The DUT holds float32 coefficients: what it reports is the float rounding of what was sent.
  const FilterConfig g = w.dut->get_filter({});
  ASSERT_EQ(g.sections.size(), 2u);
  EXPECT_EQ(g.rate_hz, 10000.0);
  EXPECT_FALSE(g.enabled);
  for (std::size_t s = 0; s < 2; ++s) {
    const Biquad& a = f.sections[s];
    const Biquad& b = g.sections[s];
    EXPECT_EQ(b.b0, static_cast<double>(static_cast<float>(a.b0)));
    EXPECT_EQ(b.b1, static_cast<double>(static_cast<float>(a.b1)));
    EXPECT_EQ(b.b2, static_cast<double>(static_cast<float>(a.b2)));
    EXPECT_EQ(b.a1, static_cast<double>(static_cast<float>(a.a1)));
    EXPECT_EQ(b.a2, static_cast<double>(static_cast<float>(a.a2)));
  }
  EXPECT_EQ(w.src.filter().sections.size(), 2u);  // it reached the DUT's physics
  // Filter off => the stream's status says so.
  w.dut->start_stream({});
  EXPECT_EQ(read_n(*w.dut, 10).back().status & sample_status::kFilterOn, 0u);
  w.dut->client().set_filter_enabled(true, {});
  const auto v = read_n(*w.dut, 50);
  EXPECT_TRUE(v.back().status & sample_status::kFilterOn);
  EXPECT_TRUE(w.dut->get_filter({}).enabled);
  EXPECT_EQ(w.dut->stats().gaps, 0u);  // commands interleaved with the stream lose nothing
}

TEST(InProcessDut, RejectedFiltersAreConfigErrors) {
  World w;
  FilterConfig unstable;
  unstable.sections = {{1, 0, 0, -2.5, 1.5}};  // poles outside the unit circle
  try {
    w.dut->set_filter(unstable, {});
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("FILTER_COMMIT"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("BAD_ARGUMENT"), std::string::npos) << e.what();
  }
  FilterConfig too_many;
  too_many.sections.resize(9);
  EXPECT_THROW(w.dut->set_filter(too_many, {}), ConfigError);
  // The old filter is untouched by the failed attempt.
  EXPECT_TRUE(w.dut->get_filter({}).sections.empty());
}

TEST(InProcessDut, FirmwareAnswersBadCommandsWithReasons) {
  World w;
  CanDutLink& c = w.dut->client();
  try {
    c.command({static_cast<Op>(0x7E), 0, 0, 0, 0}, {});
    FAIL();
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("UNKNOWN_OP"), std::string::npos) << e.what();
  }
  EXPECT_THROW(c.command({Op::FilterCoef, 0, 0, 0, 0}, {}), HardwareError);  // BAD_STATE: no FILTER_BEGIN
  EXPECT_THROW(c.command({Op::FilterGetCoef, 0, 3, 0, 0}, {}), ConfigError);  // no such section
  EXPECT_THROW(c.command({Op::GetSerial, 0, 9, 0, 0}, {}), ConfigError);      // beyond the serial
  EXPECT_EQ(w.dut->firmware().stats().bad_commands, 4u);
}

TEST(InProcessDut, HeartbeatReportsStateAndLastSample) {
  World w;
  w.dut->start_stream({});
  read_n(*w.dut, 450);
  const auto hb = w.dut->client().last_heartbeat();
  ASSERT_TRUE(hb);
  EXPECT_TRUE(hb->state & hb_state::kStreaming);
  EXPECT_NEAR(hb->temperature_c, 23.25, 0.005);
  EXPECT_GE(hb->counter, 2);
}

TEST(InProcessDut, CancellationAbortsARead) {
  World w;
  CancelSource cs;
  w.dut->start_stream({});
  // The world trips the cancel after 1 s of simulated time, like an e-stop would.
  w.clock.set_advance([&](double dt) {
    w.dut->step(dt);
    if (w.clock.now_s() > 1.0) cs.request("e-stop");
  });
  std::vector<Sample> v(100000);
  EXPECT_THROW(w.dut->read(v, cs.token()), AbortedError);
  w.dut->stop_stream();
  EXPECT_FALSE(w.dut->client().streaming());
  EXPECT_LT(w.clock.now_s(), 1.1);
}

TEST(InProcessDut, StopThenStartResumesWithoutFalseGaps) {
  World w;
  w.dut->start_stream({});
  const auto a = read_n(*w.dut, 100);
  w.dut->stop_stream();
  w.clock.sleep_for(0.5, {});  // the DUT keeps counting while not streaming
  w.dut->start_stream({});
  const auto b = read_n(*w.dut, 100);
  EXPECT_GE(b.front().seq, a.back().seq + 500);
  EXPECT_EQ(b.front().status & sample_status::kGapBefore, 0u);
  EXPECT_EQ(w.dut->stats().gaps, 0u);
}

TEST(InProcessDut, ReadWithoutStartIsAnError) {
  World w;
  std::vector<Sample> v(1);
  EXPECT_THROW(w.dut->read(v, {}), HardwareError);
}

TEST(InProcessDut, WorksWithTheProjectsEmulatedDutSource) {
  auto src = plant::make_dut_source(nullptr, 42);
  SimClock clock;
  auto dut = make_inprocess_dut(*src, clock);
  clock.set_advance([&](double dt) { dut->step(dt); });
  EXPECT_FALSE(dut->info({}).serial.empty());
  dut->start_stream({});
  const auto v = read_n(*dut, 2000);
  double mean = 0;
  for (const auto& s : v) mean += s.x_g;
  mean /= static_cast<double>(v.size());
  EXPECT_LT(std::abs(mean), 0.1);  // within the DUT's +-10 g range, near its small bias
  EXPECT_EQ(dut->stats().gaps, 0u);
}

// ---- real time (the `rig plant serve` mode) on the in-process bus ----

TEST(FirmwareRealtime, StreamsAtWallClockPaceToARealClockClient) {
  RampSource src;
  auto bus = InProcessBus::create();
  auto port = bus->open("dut");
  plant::FirmwareEmulator fw(src, *port);
  fw.start_realtime();
  RealClock clock;
  CanDutLink link(bus->open("rig"), clock);
  link.start_stream({});
  std::vector<Sample> v(200);  // 0.2 s of stream
  EXPECT_EQ(link.read(v, {}), v.size());
  link.stop_stream();
  fw.stop();
  for (std::size_t i = 1; i < v.size(); ++i) ASSERT_EQ(v[i].seq, v[0].seq + i);
  EXPECT_EQ(link.stats().gaps, 0u);
}

TEST(InProcessDut, AReaderComingBackLateIsNotSilence) {
  // The rig was busy for 0.5 s (longer than the 100 ms limit) while the DUT
  // kept streaming into the queue: that is not the DUT going silent.
  World w;
  w.dut->start_stream({});
  read_n(*w.dut, 100);
  w.clock.sleep_for(0.5, {});
  const auto v = read_n(*w.dut, 600);
  EXPECT_EQ(v.back().seq, v.front().seq + 599);
  EXPECT_EQ(w.dut->stats().gaps, 0u);
}

// Issue 15, 2: a DUT without a command channel streams from power-on and answers nothing; the
// link ([dut] commands = false) sends nothing, joins the running stream at start_stream (frames
// queued before it are stale), loses no sample at the join or after a stop/start, and refuses
// what needs a command with the reason.
TEST(InProcessDut, WithoutCommandsTheLinkJoinsTheRunningStreamAndSendsNothing) {
  InProcessDutOptions o;
  o.firmware.commands = false;
  o.link.commands = false;
  World w(o);
  EXPECT_TRUE(w.dut->firmware().streaming()) << "streams from power-on";
  EXPECT_FALSE(w.dut->command_channel().available);
  EXPECT_NE(w.dut->command_channel().reason.find("commands = false"), std::string::npos);
  w.clock.sleep_for(0.3, {});  // 300 samples queued on the rig's port, never asked for
  const uint64_t at_start = w.dut->firmware().sample_counter();
  w.dut->start_stream({});
  const auto a = read_n(*w.dut, 2000);
  EXPECT_GE(a.front().seq, at_start) << "no stale frame from before start_stream";
  EXPECT_LE(a.front().seq, at_start + 2) << "joined at once";
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].seq, a.front().seq + i);
    ASSERT_EQ(a[i].x_g, RampSource::x_of(a[i].seq));
    ASSERT_EQ(a[i].y_g, RampSource::y_of(a[i].seq));
  }
  w.dut->stop_stream();
  w.clock.sleep_for(0.25, {});
  w.dut->start_stream({});
  const auto b = read_n(*w.dut, 500);
  EXPECT_GE(b.front().seq, a.back().seq + 250);
  w.dut->stop_stream();
  const LinkStats s = w.dut->stats();
  EXPECT_EQ(s.received, 2500u);
  EXPECT_EQ(s.gaps, 0u);
  EXPECT_EQ(s.lost, 0u);
  EXPECT_EQ(s.duplicates, 0u);
  EXPECT_EQ(w.dut->client().transport_stats().tx, 0u) << "not one command sent";
  EXPECT_EQ(w.dut->firmware().stats().commands, 0u);
  EXPECT_THROW(w.dut->info({}), ConfigError);
  EXPECT_THROW(w.dut->set_filter(FilterConfig{}, {}), ConfigError);
  const LoopTestResponse lt = w.dut->loop_test({}, {});
  EXPECT_FALSE(lt.supported);
  EXPECT_NE(lt.reason.find("no command channel"), std::string::npos) << lt.reason;
  EXPECT_EQ(w.dut->firmware().stats().commands_ignored, 0u);
}

// The firmware side alone: with commands off, what the rig sends goes unanswered.
TEST(InProcessDut, FirmwareWithoutCommandsIgnoresThemAndKeepsStreaming) {
  InProcessDutOptions o;
  o.firmware.commands = false;
  o.link.command_attempts = 1;
  o.link.command_timeout_s = 0.02;
  World w(o);  // the link believes the DUT takes commands
  EXPECT_THROW(w.dut->info({}), HardwareError) << "no answer within the attempts";
  EXPECT_GE(w.dut->firmware().stats().commands_ignored, 1u);
  EXPECT_EQ(w.dut->firmware().stats().commands, 0u);
  EXPECT_TRUE(w.dut->firmware().streaming());
}
