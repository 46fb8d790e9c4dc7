// The emulated firmware streams any DBC-described layout (issue 15, 2): the encoder
// (DbcStreamEncoder, the decoder's inverse) against the rig's decoder and reassembly, for the
// shipped layouts -- the rig protocol, duts/qpa-counts (int24 counts, big-endian, 16-bit counter,
// extended id, x and y in one frame) and duts/qpa-fd (CAN FD, 7 samples of int32 counts per
// 64-byte frame) -- with 0 lost samples; gaps, duplicates, the 16-bit wrap and silence detected
// exactly as for the rig protocol; and the firmware emulator streaming qpa-counts to the rig's
// CanDutLink from a profile's [plant.firmware] section.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <set>
#include <sstream>

#include "firmware_link/can_dut_link.hpp"
#include "firmware_link/connect.hpp"
#include "firmware_link/dbc_stream.hpp"
#include "plant/firmware/firmware_config.hpp"
#include "plant/firmware/inprocess_dut.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"
#include "test_support.hpp"

using namespace rig;
using namespace rig::link;
using rig::link::testing::RampSource;

namespace {

const std::string kDuts = std::string(RIG_SOURCE_DIR) + "/duts/";

// A layout as a hardware file's [dut] section gives it (the shipped fragment, its dbc made absolute).
std::shared_ptr<const DbcStreamDecoder> shipped(const std::string& fragment) {
  std::ifstream in(kDuts + fragment);
  std::stringstream ss;
  ss << in.rdbuf();
  const toml::table t = cfg::parse_string(ss.str(), kDuts + fragment);
  return stream_decoder_from_config(*cfg::get_table(t, "dut", true));
}

std::shared_ptr<const DbcStreamDecoder> rig_protocol() {
  return std::make_shared<const DbcStreamDecoder>(rig_protocol_dbc(), rig_protocol_stream(), "rig protocol");
}

// What the DUT's output is at counter k: values across the whole range, the range ends included.
StreamSample sample_of(uint64_t k) {
  const double t = static_cast<double>(k) * 1e-3;
  StreamSample s;
  s.x_g = static_cast<float>(9.9 * std::sin(2 * std::numbers::pi * 0.37 * t) + 1e-5 * static_cast<double>(k % 7));
  s.y_g = static_cast<float>(-0.5 + 3e-6 * static_cast<double>(k % 1000));
  s.status = static_cast<uint8_t>(stream_status::kFilterOn | (k % 97 == 0 ? stream_status::kSaturated : 0));
  return s;
}

struct Streamed {
  std::vector<Sample> samples;
  LinkStats stats;
};

// Encodes samples [first, first + n) block by block (dropping the blocks whose first counter
// is in `drop`, sending twice those in `dup`) and decodes them into a reassembler.
Streamed round_trip(const std::shared_ptr<const DbcStreamDecoder>& layout, uint64_t first, std::size_t n,
                    const std::set<uint64_t>& drop = {}, const std::set<uint64_t>& dup = {}) {
  const DbcStreamEncoder enc(layout);
  StreamReassembler r = layout->make_reassembler(8);
  const auto spf = static_cast<std::size_t>(enc.samples_per_frame());
  std::vector<StreamSample> block;
  std::vector<CanFdFrame> frames;
  std::vector<StreamPart> parts;
  for (uint64_t k = first; k < first + n; k += spf) {
    block.clear();
    for (std::size_t i = 0; i < spf; ++i) block.push_back(sample_of(k + i));
    frames.clear();
    enc.encode(static_cast<uint32_t>(k), block, frames);
    if (drop.count(k)) continue;
    for (int copy = 0; copy < (dup.count(k) ? 2 : 1); ++copy)
      for (const CanFdFrame& f : frames) {
        parts.clear();
        std::string err;
        EXPECT_TRUE(layout->decode(f, parts, &err)) << "a frame of the layout";
        EXPECT_EQ(err, "");
        for (const StreamPart& p : parts) r.push_part(p);
      }
  }
  r.flush();
  Streamed s;
  s.samples.resize(r.ready());
  r.pop(s.samples);
  s.stats = r.stats();
  return s;
}

// The value a signal of `step` (in g per count) can carry for v: what the decoder must give back.
float quantised(double v, double step) { return static_cast<float>(std::nearbyint(v / step) * step); }

}  // namespace

TEST(LayoutRoundTrip, ShippedLayoutsResolveAsDocumented) {
  const auto counts = shipped("qpa-counts.dut.toml");
  EXPECT_EQ(counts->counter_bits(), 16);
  EXPECT_FALSE(DbcStreamEncoder(counts).fd());
  const DbcMessage* m = counts->dbc().find("QPA_XY");
  ASSERT_NE(m, nullptr);
  EXPECT_TRUE(m->extended);
  EXPECT_EQ(m->id, 0x18FF1000u);
  for (const auto& s : m->signals) EXPECT_TRUE(s.big_endian) << s.name;
  const auto fd = shipped("qpa-fd.dut.toml");
  EXPECT_TRUE(DbcStreamEncoder(fd).fd());
  EXPECT_EQ(fd->spec().samples_per_frame, 7);
  EXPECT_EQ(fd->counter_bits(), 16);
  EXPECT_EQ(fd->dbc().find("QPA_FD")->signal("x6")->length, 32);
}

TEST(LayoutRoundTrip, EveryShippedLayoutCarriesEverySampleAcrossThe16BitWrap) {
  struct Case {
    const char* name;
    std::shared_ptr<const DbcStreamDecoder> layout;
    double step;  // g per count of x and y (0: float32)
  };
  const Case cases[] = {{"rig protocol", rig_protocol(), 0},
                        {"qpa-counts", shipped("qpa-counts.dut.toml"), 1.25e-6},
                        {"qpa-fd", shipped("qpa-fd.dut.toml"), 1e-8}};
  for (const Case& c : cases) {
    const uint64_t first = 65536 - 700;  // through the 16-bit counter's wrap (and not at a block boundary)
    const Streamed s = round_trip(c.layout, first, 7 * 300);
    ASSERT_EQ(s.samples.size(), 7u * 300) << c.name;
    EXPECT_EQ(s.stats.lost, 0u) << c.name;
    EXPECT_EQ(s.stats.gaps, 0u) << c.name;
    EXPECT_EQ(s.stats.duplicates, 0u) << c.name;
    const uint32_t mask = c.layout->counter_bits() >= 32 ? 0xFFFFFFFFu : (1u << c.layout->counter_bits()) - 1;
    EXPECT_EQ(s.samples.front().seq, first & mask) << c.name;
    for (std::size_t i = 0; i < s.samples.size(); ++i) {
      const Sample& got = s.samples[i];
      const StreamSample want = sample_of(first + i);
      ASSERT_EQ(got.seq, s.samples.front().seq + i) << c.name << ": widened past the wrap";
      if (c.step == 0) {
        ASSERT_EQ(got.x_g, want.x_g) << c.name;
        ASSERT_EQ(got.y_g, want.y_g) << c.name;
      } else {
        ASSERT_NEAR(got.x_g, quantised(want.x_g, c.step), 1e-6 * c.step + 1e-7 * std::abs(want.x_g)) << c.name << " " << i;
        ASSERT_NEAR(got.y_g, quantised(want.y_g, c.step), 1e-6 * c.step + 1e-7) << c.name << " " << i;
      }
    }
  }
}

TEST(LayoutRoundTrip, StatusBitsTravelPerSampleOrPerFrame) {
  // The rig protocol carries each sample's flags; qpa-fd one status byte for its 7 samples (their OR).
  const Streamed rp = round_trip(rig_protocol(), 0, 200);
  for (const Sample& s : rp.samples) EXPECT_EQ(s.status, sample_of(s.seq).status) << s.seq;
  const Streamed fd = round_trip(shipped("qpa-fd.dut.toml"), 0, 7 * 30);
  for (const Sample& s : fd.samples) {
    uint8_t any = 0;
    const uint64_t b = s.seq / 7 * 7;
    for (uint64_t k = b; k < b + 7; ++k) any |= sample_of(k).status;
    EXPECT_EQ(s.status, any) << s.seq;
  }
  const Streamed counts = round_trip(shipped("qpa-counts.dut.toml"), 0, 10);
  for (const Sample& s : counts.samples) EXPECT_EQ(s.status, 0u) << "the counts layout has no status";
}

TEST(LayoutRoundTrip, GapsAndDuplicatesAreLocatedForEveryLayout) {
  for (const auto& [name, layout] : {std::pair{"qpa-counts", shipped("qpa-counts.dut.toml")},
                                     std::pair{"qpa-fd", shipped("qpa-fd.dut.toml")}}) {
    const uint64_t spf = static_cast<uint64_t>(layout->spec().samples_per_frame);
    const uint64_t first = 65536 - 70 * spf;
    // Frames lost: one block just before the wrap, two after it; one block sent twice.
    const uint64_t lost_a = first + 40 * spf, lost_b = first + 90 * spf;
    const Streamed s = round_trip(layout, first, 140 * spf, {lost_a, lost_b, lost_b + spf}, {first + 10 * spf});
    EXPECT_EQ(s.stats.gaps, 2u) << name;
    EXPECT_EQ(s.stats.lost, 3 * spf) << name;
    EXPECT_EQ(s.stats.duplicates, 2 * (spf == 1 ? 1 : spf)) << name << ": x and y of each sample of the frame sent twice";
    ASSERT_EQ(s.stats.gap_list.size(), 2u);
    EXPECT_EQ(s.stats.gap_list[0], std::make_pair(lost_a, spf)) << name;
    EXPECT_EQ(s.stats.gap_list[1], std::make_pair(lost_b, 2 * spf)) << name << ": located past the wrap";
    EXPECT_EQ(s.samples.size(), 137 * spf);
  }
}

// x on multiplexer page 0 and y on page 1 of one message: a layout the rig reads from a real DUT,
// which the emulator refused ("needs multiplexer values 0 and 1 in one frame", a review). It is
// sent as one frame per page, and every sample comes back whole.
TEST(LayoutRoundTrip, AMultiplexedLayoutIsSentAsOneFramePerPage) {
  const auto db = std::make_shared<const Dbc>(Dbc::parse(
      "BO_ 512 PAGES: 8 D\n SG_ page M : 0|8@1+ (1,0) [0|1] \"\" R\n SG_ n : 8|16@1+ (1,0) [0|65535] \"\" R\n"
      " SG_ x m0 : 24|32@1- (1e-06,0) [0|0] \"g\" R\n SG_ y m1 : 24|32@1- (1e-06,0) [0|0] \"g\" R\n",
      "pages.dbc"));
  DbcStreamSpec sp;
  sp.counter = "PAGES.n";
  sp.x = "PAGES.x";
  sp.y = "PAGES.y";
  const auto layout = std::make_shared<const DbcStreamDecoder>(db, sp, "t");
  const DbcStreamEncoder enc(layout);
  std::vector<CanFdFrame> frames;
  const StreamSample one = sample_of(3);
  enc.encode(3, std::span<const StreamSample>(&one, 1), frames);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].data[0], 0) << "page 0 first";
  EXPECT_EQ(frames[1].data[0], 1);
  const Streamed s = round_trip(layout, 65000, 1000);  // across the 16-bit wrap
  ASSERT_EQ(s.samples.size(), 1000u);
  EXPECT_EQ(s.stats.gaps, 0u);
  for (std::size_t i = 0; i < s.samples.size(); ++i) {
    const StreamSample want = sample_of(65000 + i);
    EXPECT_EQ(s.samples[i].seq, 65000 + i);
    EXPECT_FLOAT_EQ(s.samples[i].x_g, quantised(want.x_g, 1e-6)) << i;
    EXPECT_FLOAT_EQ(s.samples[i].y_g, quantised(want.y_g, 1e-6)) << i;
  }
}

namespace {

// The in-process emulated firmware with a [plant.firmware] section, and the rig's link as the
// hardware file's [dut] section would configure it.
struct LayoutWorld {
  RampSource src;
  SimClock clock;
  std::unique_ptr<InProcessDutLink> dut;
  explicit LayoutWorld(const std::string& firmware_toml, const std::string& dut_fragment, bool commands = true) {
    const toml::table fw = cfg::parse_string(firmware_toml, kDuts + "profile.toml");
    InProcessDutOptions o;
    o.firmware = plant::firmware_options(&fw);
    o.firmware.commands = commands;
    o.link.stream = shipped(dut_fragment);
    o.link.commands = commands;
    dut = make_inprocess_dut(src, clock, o);
    clock.set_advance([this](double dt) { dut->step(dt); });
  }
};

const char* kCountsFirmware =
    "dbc = \"qpa-counts.dbc\"\n[stream]\ncounter = \"QPA_XY.cnt\"\nx = \"QPA_XY.x_counts\"\ny = \"QPA_XY.y_counts\"\n";

}  // namespace

TEST(LayoutRoundTrip, EmulatedFirmwareStreamsTheCountsLayoutToTheRigsLink) {
  LayoutWorld w(kCountsFirmware, "qpa-counts.dut.toml");
  w.clock.sleep_for(0.2, {});
  w.dut->start_stream({});
  std::vector<Sample> v(70000);  // more than one period of the 16-bit counter
  ASSERT_EQ(w.dut->read(v, {}), v.size());
  w.dut->stop_stream();
  for (std::size_t i = 0; i < v.size(); ++i) {
    ASSERT_EQ(v[i].seq, v.front().seq + i);
    // The ramp's firmware counter starts at 0 with the source: counter k carries the ramp's k.
    ASSERT_NEAR(v[i].x_g, quantised(RampSource::x_of(v[i].seq), 1.25e-6), 1e-9) << i;
    ASSERT_NEAR(v[i].y_g, quantised(RampSource::y_of(v[i].seq), 1.25e-6), 1e-9) << i;
  }
  const LinkStats s = w.dut->stats();
  EXPECT_EQ(s.received, v.size());
  EXPECT_EQ(s.lost, 0u);
  EXPECT_EQ(s.duplicates, 0u);
  EXPECT_EQ(w.dut->info({}).output_rate_hz, 1000.0);
}

TEST(LayoutRoundTrip, EmulatedFirmwareFaultsOnTheCountsLayoutAreFoundByTheLink) {
  LayoutWorld w(kCountsFirmware, "qpa-counts.dut.toml", false);  // no command channel either
  plant::FirmwareFaults f;
  f.drop_samples = {{65530, 12}};  // across the wrap
  f.duplicate_samples = {66000};
  f.silent_from = 67000;
  w.dut->firmware().set_faults(f);
  w.clock.sleep_for(65.0, {});
  w.dut->start_stream({});
  std::vector<Sample> v(1500);
  ASSERT_EQ(w.dut->read(v, {}), v.size());
  try {
    for (;;) w.dut->read(v, {});
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("silent"), std::string::npos) << e.what();
  }
  const LinkStats s = w.dut->stats();
  EXPECT_EQ(s.gaps, 1u);
  EXPECT_EQ(s.lost, 12u);
  ASSERT_EQ(s.gap_list.size(), 1u);
  EXPECT_EQ(s.gap_list[0], std::make_pair(uint64_t{65530}, uint64_t{12})) << "located on the widened counter";
  EXPECT_EQ(s.duplicates, 2u) << "the one frame carrying x and y, sent twice: its x and its y";
}

// CAN FD on the in-process bus: 7 samples per 64-byte frame, every sample, the wrap, a lost
// frame located as 7 samples, silence declared.
TEST(LayoutRoundTrip, EmulatedFirmwareStreamsTheCanFdLayoutToTheRigsLink) {
  const std::string fd =
      "dbc = \"qpa-fd.dbc\"\n[stream]\ncounter = \"QPA_FD.cnt\"\nx = \"QPA_FD.x\"\ny = \"QPA_FD.y\"\n"
      "status = \"QPA_FD.status\"\nfilter_on_bit = 0\nsaturated_bit = 1\nloop_fault_bit = 2\nsamples_per_frame = 7\n";
  LayoutWorld w(fd, "qpa-fd.dut.toml");
  plant::FirmwareFaults f;
  f.drop_samples = {{65540, 1}};  // takes its whole frame
  f.silent_from = 70000;
  w.dut->firmware().set_faults(f);
  w.clock.sleep_for(64.0, {});
  w.dut->start_stream({});
  std::vector<Sample> v(5000);
  ASSERT_EQ(w.dut->read(v, {}), v.size());
  const uint64_t first = v.front().seq;  // blocks of 7 start with the stream
  for (std::size_t i = 1; i < v.size(); ++i) {
    if (v[i].status & sample_status::kGapBefore) {
      EXPECT_EQ(v[i].seq, v[i - 1].seq + 8);
      continue;
    }
    ASSERT_EQ(v[i].seq, v[i - 1].seq + 1) << i;
    ASSERT_NEAR(v[i].x_g, RampSource::x_of(v[i].seq), 1e-8) << i;
    ASSERT_NEAR(v[i].y_g, RampSource::y_of(v[i].seq), 1e-8) << i;
    ASSERT_TRUE(v[i].status & sample_status::kFilterOn);
  }
  EXPECT_THROW(for (;;) w.dut->read(v, {}), HardwareError);
  const LinkStats s = w.dut->stats();
  EXPECT_EQ(s.gaps, 1u);
  EXPECT_EQ(s.lost, 7u);
  ASSERT_EQ(s.gap_list.size(), 1u);
  // The frame that carried 65540, located past the wrap.
  EXPECT_EQ((s.gap_list[0].first - first) % 7, 0u);
  EXPECT_LE(s.gap_list[0].first, 65540u);
  EXPECT_GT(s.gap_list[0].first + 7, 65540u);
  EXPECT_EQ(s.duplicates, 0u);
  EXPECT_GT(w.dut->client().transport_stats().rx, 700u);
}

TEST(LayoutRoundTrip, AClassicTransportRefusesCanFdFramesSayingSo) {
  struct Classic final : CanTransport {
    void send(const CanFrame&) override {}
    std::optional<RxFrame> receive(double, const CancelToken&) override { return std::nullopt; }
    double now_s() const override { return 0; }
    void set_filters(std::span<const CanFilter>) override {}
    TransportStats stats() const override { return {}; }
    std::string name() const override { return "classic0"; }
  } t;
  try {
    t.send_fd(CanFdFrame{});
    FAIL();
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("classic0: cannot send a CAN FD frame"), std::string::npos) << e.what();
  }
}
