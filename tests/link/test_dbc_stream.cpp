// DBC-described DUT streams (firmware_link/dbc_stream.hpp): layouts other than the rig
// protocol's (tests/data/dbc/dut-layouts.dbc) reach the reassembly with the same
// guarantees: a 16-bit counter widened across its wrap, reordering within the window,
// gaps located, duplicates counted, silence declared; and the rig protocol itself,
// described by the shipped DBC, decodes to exactly what the codec gives.
#include <fstream>

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "firmware_link/can_dut_link.hpp"
#include "firmware_link/connect.hpp"
#include "firmware_link/dbc_stream.hpp"
#include "firmware_link/inprocess_bus.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"

using namespace rig;
using namespace rig::link;
namespace ss = rig::sample_status;

namespace {

const std::string kLayouts = std::string(RIG_SOURCE_DIR) + "/tests/data/dbc/dut-layouts.dbc";

std::shared_ptr<const Dbc> layouts() {
  static const auto db = std::make_shared<const Dbc>(Dbc::parse_file(kLayouts));
  return db;
}

// A frame of `msg` with the given physical values (the encoder the DUT would be).
CanFdFrame make(const Dbc& db, const std::string& msg, const std::map<std::string, double>& v) {
  const DbcMessage* m = db.find(msg);
  EXPECT_NE(m, nullptr) << msg;
  CanFdFrame f;
  f.id = m->id;
  f.extended = m->extended;
  f.len = static_cast<uint8_t>(m->dlc);
  f.fd = m->dlc > 8;
  for (const auto& [name, value] : v) {
    const DbcSignal* s = m->signal(name);
    EXPECT_NE(s, nullptr) << msg << "." << name;
    dbc_insert_raw(std::span<uint8_t>(f.data.data(), f.len), s->start, s->length, s->big_endian, dbc_raw_of(*s, value));
  }
  return f;
}

// The error a decoder built from `spec` gives, placed as a hardware file's [dut.stream]; "no error".
std::string spec_error(std::shared_ptr<const Dbc> db, DbcStreamSpec spec) {
  try {
    DbcStreamDecoder d(std::move(db), std::move(spec), "hw.toml:9:1: [dut.stream]");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "no error";
}

DbcStreamSpec xy_spec() {
  DbcStreamSpec s;
  s.counter = "ACC_XY.cnt";
  s.x = "ACC_XY.x";
  s.y = "ACC_XY.y";
  return s;
}

double x_of(uint64_t k) { return std::round((static_cast<double>(k % 1000) * 1e-4 - 0.05) / 2e-6) * 2e-6; }

CanFdFrame xy_frame(uint64_t k) {
  return make(*layouts(), "ACC_XY", {{"cnt", static_cast<double>(k % 65536)}, {"x", x_of(k)}, {"y", -x_of(k)}});
}

struct Pipe {
  DbcStreamDecoder dec;
  StreamReassembler reasm;
  std::vector<StreamPart> parts;
  Pipe(DbcStreamSpec s, uint32_t window = 8) : dec(layouts(), std::move(s), "test"), reasm(dec.make_reassembler(window)) {}
  void push(const CanFdFrame& f) {
    parts.clear();
    std::string err;
    ASSERT_TRUE(dec.decode(f, parts, &err));
    ASSERT_EQ(err, "");
    for (const auto& p : parts) reasm.push_part(p);
  }
  std::vector<Sample> drain() {
    std::vector<Sample> out(reasm.ready());
    reasm.pop(out);
    return out;
  }
};

}  // namespace

TEST(DbcStream, RigProtocolThroughTheShippedDbcEqualsTheCodec) {
  const DbcStreamDecoder dec(rig_protocol_dbc(), rig_protocol_stream(), "rig");
  EXPECT_EQ(dec.counter_bits(), 24);
  std::mt19937 rng(7);
  for (int i = 0; i < 2000; ++i) {
    StreamHalf h;
    h.channel = i % 2 ? Channel::Y : Channel::X;
    h.seq24 = rng() & kSeqMask;
    h.status = static_cast<uint8_t>(rng() & 7);
    h.value_g = std::uniform_real_distribution<float>(-12, 12)(rng);
    std::vector<StreamPart> parts;
    ASSERT_TRUE(dec.decode(encode(h), parts));
    ASSERT_EQ(parts.size(), 1u);
    EXPECT_EQ(parts[0].channel, h.channel);
    EXPECT_EQ(parts[0].counter, h.seq24);
    EXPECT_EQ(parts[0].status, h.status);
    EXPECT_EQ(parts[0].value_g, h.value_g);
  }
  std::vector<StreamPart> parts;
  EXPECT_FALSE(dec.decode(encode(Heartbeat{}), parts));  // not a stream frame
  EXPECT_FALSE(dec.decode(encode(Command{}), parts));
}

TEST(DbcStream, XAndYInOneExtendedBigEndianFrameAcrossThe16BitWrap) {
  Pipe p(xy_spec());
  EXPECT_EQ(p.dec.counter_bits(), 16);
  const uint64_t k0 = 65500;
  for (uint64_t k = k0; k < k0 + 200; ++k) p.push(xy_frame(k));
  const auto out = p.drain();
  ASSERT_EQ(out.size(), 200u);
  for (std::size_t i = 0; i < out.size(); ++i) {
    EXPECT_EQ(out[i].seq, k0 + i);  // widened: 65535 is followed by 65536, not 0
    EXPECT_NEAR(out[i].x_g, x_of(k0 + i), 1e-6);
    EXPECT_NEAR(out[i].y_g, -x_of(k0 + i), 1e-6);
    EXPECT_EQ(out[i].status, 0u);
  }
  EXPECT_EQ(p.reasm.stats().gaps, 0u);
  EXPECT_EQ(p.reasm.stats().duplicates, 0u);
}

TEST(DbcStream, GapsAreLocatedDuplicatesCountedReorderingAbsorbed) {
  Pipe p(xy_spec());
  const uint64_t k0 = 65530;  // the gap straddles the wrap
  for (uint64_t k = k0; k < k0 + 40; ++k) {
    if (k >= k0 + 4 && k < k0 + 9) continue;  // 5 lost: 65534..65538
    if (k == k0 + 20) {                        // 20 and 21 swapped
      p.push(xy_frame(k + 1));
      p.push(xy_frame(k));
      continue;
    }
    if (k == k0 + 21) continue;
    p.push(xy_frame(k));
    if (k == k0 + 30) p.push(xy_frame(k));  // a duplicate
  }
  p.reasm.flush();
  const auto out = p.drain();
  ASSERT_EQ(out.size(), 35u);
  const LinkStats& st = p.reasm.stats();
  EXPECT_EQ(st.gaps, 1u);
  EXPECT_EQ(st.lost, 5u);
  ASSERT_EQ(st.gap_list.size(), 1u);
  EXPECT_EQ(st.gap_list[0].first, k0 + 4);
  EXPECT_EQ(st.gap_list[0].second, 5u);
  EXPECT_EQ(st.duplicates, 2u);  // counted per part, as for the rig protocol: a frame carrying x and y is two
  for (const auto& s : out) EXPECT_EQ((s.status & ss::kGapBefore) != 0, s.seq == k0 + 9) << s.seq;
  for (std::size_t i = 1; i < out.size(); ++i) EXPECT_GT(out[i].seq, out[i - 1].seq);  // in order after the swap
}

TEST(DbcStream, Int32CountsInTwoFramesWithStatusBits) {
  DbcStreamSpec s;
  s.counter = "ACC_X.cnt";
  s.x = "ACC_X.x_counts";
  s.y = "ACC_Y.y_counts";
  s.status = "ACC_X.st";
  s.saturated_bit = 0;
  s.filter_on_bit = 3;
  s.loop_fault_bit = 5;
  Pipe p(s);
  const auto& db = *layouts();
  // x = 0.123456789 g = 123.456789 mg = 12345679 counts of 1e-5 mg.
  p.push(make(db, "ACC_Y", {{"cnt", 7}, {"st", 1 << 3}, {"y_counts", -45.6789}}));  // y before x: reordered
  p.push(make(db, "ACC_X", {{"cnt", 7}, {"st", 1 << 3}, {"x_counts", 123.45679}}));
  p.push(make(db, "ACC_X", {{"cnt", 8}, {"st", (1 << 0) | (1 << 5) | (1 << 1)}, {"x_counts", -1}}));
  p.push(make(db, "ACC_Y", {{"cnt", 8}, {"st", (1 << 0) | (1 << 5) | (1 << 1)}, {"y_counts", 1}}));
  const auto out = p.drain();
  ASSERT_EQ(out.size(), 2u);
  EXPECT_NEAR(out[0].x_g, 0.12345679, 1e-8);
  EXPECT_NEAR(out[0].y_g, -0.0456789, 1e-8);
  EXPECT_EQ(out[0].status, stream_status::kFilterOn);
  EXPECT_EQ(out[1].status, stream_status::kSaturated | stream_status::kLoopFault);  // bit 1 means nothing here
  EXPECT_NEAR(out[1].x_g, -1e-3, 1e-9);
  EXPECT_EQ(p.dec.filters().size(), 2u);
  EXPECT_TRUE(p.dec.filters()[0].extended);
}

TEST(DbcStream, CanFdFramesOfEightSamples) {
  DbcStreamSpec s;
  s.counter = "FD_BLOCK.counter";
  s.x = "FD_BLOCK.x";
  s.y = "FD_BLOCK.y";
  s.status = "FD_BLOCK.status";
  s.filter_on_bit = 0;
  s.samples_per_frame = 8;
  Pipe p(s, 16);
  const auto& db = *layouts();
  auto block = [&](uint64_t k0) {
    std::map<std::string, double> v{{"counter", static_cast<double>(k0 % 65536)}, {"status", 1}};
    for (int i = 0; i < 8; ++i) {
      v["x" + std::to_string(i)] = std::round(x_of(k0 + i) / 1e-7) * 1e-7;
      v["y" + std::to_string(i)] = -std::round(x_of(k0 + i) / 1e-6) * 1e-6;
    }
    return make(db, "FD_BLOCK", v);
  };
  const uint64_t k0 = 65536 - 8 * 5;
  for (int b = 0; b < 12; ++b)
    if (b != 6) p.push(block(k0 + 8 * static_cast<uint64_t>(b)));  // frame 6 lost: 8 samples across the wrap
  p.push(block(k0 + 8 * 11));                                       // frame 11 again
  p.reasm.flush();
  const auto out = p.drain();
  ASSERT_EQ(out.size(), 88u);
  EXPECT_EQ(p.reasm.stats().gaps, 1u);
  EXPECT_EQ(p.reasm.stats().lost, 8u);
  EXPECT_EQ(p.reasm.stats().gap_list.at(0).first, k0 + 48);
  EXPECT_EQ(p.reasm.stats().duplicates, 16u);  // 8 samples x 2 channels
  EXPECT_EQ(out[0].seq, k0);
  EXPECT_EQ(out.back().seq, k0 + 95);  // widened through 65535 -> 65536
  for (const auto& smp : out) {
    EXPECT_NEAR(smp.x_g, x_of(smp.seq), 1e-7);
    EXPECT_NEAR(smp.y_g, -x_of(smp.seq), 1e-6);
    EXPECT_EQ(smp.status & stream_status::kFilterOn, stream_status::kFilterOn);
  }
  // A frame padded to another FD length than the DBC's is malformed, not decoded.
  CanFdFrame bad = block(0);
  bad.len = 48;
  std::vector<StreamPart> parts;
  std::string err;
  EXPECT_TRUE(p.dec.decode(bad, parts, &err));
  EXPECT_TRUE(parts.empty());
  EXPECT_EQ(err, "FD_BLOCK: length 48, DBC says 64");
}

TEST(DbcStream, MultiplexedXAndYPages) {
  DbcStreamSpec s;
  s.counter = "MUXED.cnt";
  s.x = "MUXED.x";
  s.y = "MUXED.y";
  Pipe p(s);
  const auto& db = *layouts();
  for (int k = 0; k < 10; ++k) {
    p.push(make(db, "MUXED", {{"page", 0}, {"cnt", k}, {"x", k * 0.5}}));
    p.push(make(db, "MUXED", {{"page", 1}, {"cnt", k}, {"y", -k * 0.25}}));
  }
  const auto out = p.drain();
  ASSERT_EQ(out.size(), 10u);
  EXPECT_EQ(out[9].x_g, 4.5f);
  EXPECT_EQ(out[9].y_g, -2.25f);
}

TEST(DbcStream, WithoutYASampleIsItsX) {
  DbcStreamSpec s = xy_spec();
  s.y.clear();
  Pipe p(s);
  p.push(xy_frame(3));
  p.push(xy_frame(4));
  const auto out = p.drain();
  ASSERT_EQ(out.size(), 2u);
  EXPECT_TRUE(std::isnan(out[0].y_g));
}

TEST(DbcStream, SpecErrorsNameTheProblem) {
  auto error = [](DbcStreamSpec s) { return spec_error(layouts(), std::move(s)); };
  DbcStreamSpec s = xy_spec();
  s.x = "ACC_XY.nope";
  EXPECT_EQ(error(s), "hw.toml:9:1: [dut.stream]: x = \"ACC_XY.nope\": no signal nope in ACC_XY");
  s = xy_spec();
  s.counter = "NOPE.cnt";
  EXPECT_EQ(error(s), "hw.toml:9:1: [dut.stream]: counter = \"NOPE.cnt\": the DBC has no message NOPE");
  s = xy_spec();
  s.y = "ACC_Y.y";
  EXPECT_EQ(error(s), "hw.toml:9:1: [dut.stream]: y = \"ACC_Y.y\": no signal y in ACC_Y");
  s = xy_spec();
  s.y = "FD_BLOCK.y0";  // a message whose counter has another name: said at y's own line
  s.key_where["y"] = "hw.toml:12:1: [dut.stream]";
  EXPECT_EQ(error(s), "hw.toml:12:1: [dut.stream]: y = \"FD_BLOCK.y0\": message FD_BLOCK carries part of a sample but "
                      "no counter signal 'cnt'");
  s = xy_spec();  // FD_BLOCK holds x0..x7: a frame of 8 samples read as 7 would drop one per frame
  s.counter = "FD_BLOCK.counter";
  s.x = "FD_BLOCK.x";
  s.y = "FD_BLOCK.y";
  s.samples_per_frame = 7;
  s.key_where["samples_per_frame"] = "hw.toml:14:1: [dut.stream]";
  EXPECT_EQ(error(s), "hw.toml:14:1: [dut.stream]: samples_per_frame = 7: message FD_BLOCK also has x7 (x of a sample "
                      "8): a frame's samples are numbered 0..samples_per_frame-1, and this one would never be read");
  s = xy_spec();
  s.counter = "MUXED.x";
  EXPECT_EQ(error(s), "hw.toml:9:1: [dut.stream]: counter MUXED.x must be an integer signal of 2..32 bits (has 32, float)");
  s = xy_spec();
  s.status = "ACC_XY.cnt";
  EXPECT_EQ(error(s), "hw.toml:9:1: [dut.stream]: status = \"ACC_XY.cnt\" names no bit (filter_on_bit, saturated_bit, "
                      "loop_fault_bit)");
  s = xy_spec();
  s.x = "ACC_XY";
  EXPECT_EQ(error(s), "hw.toml:9:1: [dut.stream]: x = \"ACC_XY\" is not MESSAGE.SIGNAL");
  // A technician's review: a flag bit the status signal does not have, two flags on one bit and
  // a sample signal without a unit (taken as g before) were accepted.
  s = DbcStreamSpec{};
  s.counter = "ACC_X.cnt", s.x = "ACC_X.x_counts", s.y = "ACC_Y.y_counts", s.status = "ACC_X.st";
  s.loop_fault_bit = 12;
  EXPECT_EQ(error(s), "hw.toml:9:1: [dut.stream]: loop_fault_bit = 12 is beyond status ACC_X.st, which has 8 bits (0..7)");
  s.loop_fault_bit = 3, s.saturated_bit = 3;
  EXPECT_EQ(error(s), "hw.toml:9:1: [dut.stream]: loop_fault_bit = 3 is also saturated_bit: each flag needs its own bit");
  s.saturated_bit = 0;
  s.key_where["loop_fault_bit"] = "hw.toml:14:18: [dut.stream]";  // where the key was written
  EXPECT_EQ(error(s), "no error");
  s.loop_fault_bit = 9;
  EXPECT_EQ(error(s), "hw.toml:14:18: [dut.stream]: loop_fault_bit = 9 is beyond status ACC_X.st, which has 8 bits (0..7)");
  const auto unitless = std::make_shared<const Dbc>(Dbc::parse(
      "VERSION \"\"\nBU_: DUT\nBO_ 288 A: 8 DUT\n SG_ cnt : 0|16@1+ (1,0) [0|65535] \"\" DUT\n"
      " SG_ x : 16|32@1- (1e-06,0) [0|0] \"\" DUT\n",
      "unitless.dbc"));
  DbcStreamSpec u;
  u.counter = "A.cnt", u.x = "A.x";
  EXPECT_EQ(spec_error(unitless, u), "hw.toml:9:1: [dut.stream]: x A.x has no unit in the DBC; give it the acceleration "
                                     "unit its factor yields (g, mg, ug or m/s^2)");
  u.key_where["x"] = "hw.toml:11:5: [dut.stream]";  // named at x's line where the file gave it
  EXPECT_EQ(spec_error(unitless, u).rfind("hw.toml:11:5: [dut.stream]: x A.x has no unit", 0), 0u) << spec_error(unitless, u);
  // Micrograms as CANdb++ writes them (Windows-1252: the byte 0xB5), as UTF-8 and with the Greek
  // mu a keyboard gives: all 1e-6 g (the 1252 byte was refused, shown raw). A unit that is no
  // acceleration is shown escaped where it is not text.
  const auto with_unit = [](const std::string& unit) {
    return std::make_shared<const Dbc>(Dbc::parse("VERSION \"\"\nBU_: DUT\nBO_ 288 A: 8 DUT\n SG_ cnt : 0|16@1+ (1,0) "
                                                  "[0|65535] \"\" DUT\n SG_ x : 16|32@1- (1,0) [0|0] \"" + unit + "\" DUT\n",
                                                  "unit.dbc"));
  };
  u.key_where.clear();
  for (const char* ug : {"\xB5g", "\xC2\xB5g", "\xCE\xBCg"}) EXPECT_EQ(spec_error(with_unit(ug), u), "no error") << ug;
  EXPECT_EQ(spec_error(with_unit("\x1b[2Jg"), u),
            "hw.toml:9:1: [dut.stream]: x A.x has unit '\\x1B[2Jg', not an acceleration (g, mg, ug, m/s^2)");
  // A scaled counter: its physical value is not the count the stream reads (its raw value was
  // used silently, a review); refused naming its DBC file and line, in the message `counter` names and in
  // another message carrying part of a sample.
  const auto scaled = std::make_shared<const Dbc>(Dbc::parse(
      "VERSION \"\"\nBU_: DUT\nBO_ 288 A: 8 DUT\n SG_ cnt : 0|16@1+ (0.5,0) [0|32767] \"\" DUT\n"
      " SG_ x : 16|32@1- (1e-06,0) [0|0] \"g\" DUT\nBO_ 289 B: 8 DUT\n SG_ cnt : 0|16@1+ (1,1) [0|65535] \"\" DUT\n"
      " SG_ y : 16|32@1- (1e-06,0) [0|0] \"g\" DUT\nBO_ 290 C: 8 DUT\n SG_ cnt : 0|16@1+ (1,0) [0|65535] \"\" DUT\n"
      " SG_ x : 16|32@1- (1e-06,0) [0|0] \"g\" DUT\n",
      "scaled.dbc"));
  DbcStreamSpec sc;
  sc.counter = "A.cnt", sc.x = "A.x";
  EXPECT_EQ(spec_error(scaled, sc), "hw.toml:9:1: [dut.stream]: counter A.cnt is scaled in the DBC (0.5,0), scaled.dbc:4: "
                                    "a sample counter is a whole number, factor 1 and offset 0");
  sc.counter = "C.cnt", sc.x = "C.x", sc.y = "B.y";
  EXPECT_EQ(spec_error(scaled, sc), "hw.toml:9:1: [dut.stream]: counter B.cnt is scaled in the DBC (1,1), scaled.dbc:7: "
                                    "a sample counter is a whole number, factor 1 and offset 0");
  sc.y = "";
  EXPECT_EQ(spec_error(scaled, sc), "no error");
  // A counter on page 1 only and x on page 0: no frame with x would carry a counter.
  const auto paged = std::make_shared<const Dbc>(Dbc::parse(
      "VERSION \"\"\nBU_: DUT\nBO_ 289 P: 8 DUT\n SG_ page M : 0|8@1+ (1,0) [0|1] \"\" DUT\n"
      " SG_ cnt m1 : 8|16@1+ (1,0) [0|65535] \"\" DUT\n SG_ x m0 : 32|32@1- (1e-06,0) [0|0] \"g\" DUT\n",
      "paged.dbc"));
  DbcStreamSpec pg;
  pg.counter = "P.cnt", pg.x = "P.x";
  EXPECT_EQ(spec_error(paged, pg), "hw.toml:9:1: [dut.stream]: x P.x is on multiplexer page 0, but counter P.cnt only "
                                   "on page 1: those frames would carry no counter");
  // A status on a page of its own, where no x or y is: its flags would reach no sample (the
  // decoder gives a frame's flags to that frame's samples; a code review).
  const auto lone = std::make_shared<const Dbc>(Dbc::parse(
      "VERSION \"\"\nBU_: DUT\nBO_ 289 P: 8 DUT\n SG_ page M : 0|8@1+ (1,0) [0|3] \"\" DUT\n"
      " SG_ cnt : 8|16@1+ (1,0) [0|65535] \"\" DUT\n SG_ x m0 : 32|16@1- (1e-06,0) [0|0] \"g\" DUT\n"
      " SG_ y m1 : 32|16@1- (1e-06,0) [0|0] \"g\" DUT\n SG_ st m1 : 48|8@1+ (1,0) [0|255] \"\" DUT\n"
      " SG_ sat m3 : 56|1@1+ (1,0) [0|1] \"\" DUT\n",
      "lone.dbc"));
  DbcStreamSpec ls;
  ls.counter = "P.cnt", ls.x = "P.x", ls.y = "P.y", ls.status = "P.st", ls.saturated_bit = 1;
  EXPECT_EQ(spec_error(lone, ls), "no error") << "a status beside y on page 1";
  ls.status = "", ls.saturated_bit = -1, ls.saturated = "P.sat";
  EXPECT_EQ(spec_error(lone, ls), "hw.toml:9:1: [dut.stream]: P.sat is on multiplexer page 3, where P carries neither x "
                                  "nor y: its flags would reach no sample");
}

// A layout whose sample shares bits with its counter or a flag would decode plausible numbers;
// it is refused with both roles, signals and DBC lines, as is one signal named in two roles.
// Aliases the stream does not read through (a status word holding the counter, of which only
// the named flag bits are read; a status word and its one-bit flags) and signals of two
// different multiplexed pages stay allowed.
TEST(DbcStream, SignalsSharingBitsWithTheSampleAreRefused) {
  const std::string text =
      "VERSION \"\"\nBS_:\nBU_: DUT RIG\n"
      "BO_ 300 OVL: 8 DUT\n"
      " SG_ cnt : 0|16@1+ (1,0) [0|65535] \"\" RIG\n"     // line 5
      " SG_ x : 8|24@1- (1e-06,0) [-8|8] \"g\" RIG\n"       // line 6: bits 8..31, inside cnt's 8..15
      " SG_ x_ok : 16|24@1- (1e-06,0) [-8|8] \"g\" RIG\n"   // line 7: bits 16..39
      " SG_ st : 40|8@1+ (1,0) [0|255] \"\" RIG\n"          // line 8
      " SG_ sat : 40|1@1+ (1,0) [0|1] \"\" RIG\n"           // line 9: st's bit 0, an alias
      " SG_ bad_flag : 39|1@1+ (1,0) [0|1] \"\" RIG\n"      // line 10: x_ok's top bit
      "BO_ 301 PAGES: 8 DUT\n"
      " SG_ cnt : 0|16@1+ (1,0) [0|65535] \"\" RIG\n"
      " SG_ page M : 16|8@1+ (1,0) [0|255] \"\" RIG\n"
      " SG_ x m0 : 24|32@1- (1e-06,0) [-8|8] \"g\" RIG\n"
      " SG_ y m1 : 24|32@1- (1e-06,0) [-8|8] \"g\" RIG\n"
      "BO_ 302 WORD: 8 DUT\n"
      " SG_ x : 0|16@1- (1e-04,0) [-3|3] \"g\" RIG\n"
      " SG_ y : 16|16@1- (1e-04,0) [-3|3] \"g\" RIG\n"
      " SG_ st : 32|16@1+ (1,0) [0|65535] \"\" RIG\n"       // line 19: flags in bits 0..2, the counter in 8..15
      " SG_ cnt : 40|8@1+ (1,0) [0|255] \"\" RIG\n";        // line 20
  const auto db = std::make_shared<const Dbc>(Dbc::parse(text, "ovl.dbc"));
  auto error = [&](DbcStreamSpec s) { return spec_error(db, std::move(s)); };
  DbcStreamSpec s;
  s.counter = "OVL.cnt";
  s.x = "OVL.x";
  EXPECT_EQ(error(s), "hw.toml:9:1: [dut.stream]: counter OVL.cnt (0|16, ovl.dbc:5) and x OVL.x (8|24, ovl.dbc:6) "
                      "share bits: the counter, x and y each need their own");
  s.x = "OVL.x_ok";
  EXPECT_EQ(error(s), "no error");
  s.status = "OVL.st";
  s.saturated_bit = 0;
  EXPECT_EQ(error(s), "no error");
  DbcStreamSpec f;
  f.counter = "OVL.cnt";
  f.x = "OVL.x_ok";
  f.saturated = "OVL.sat";
  EXPECT_EQ(error(f), "no error");  // sat is st's bit 0 (an alias), not x's
  f.saturated = "OVL.bad_flag";
  EXPECT_NE(error(f).find("x OVL.x_ok (16|24, ovl.dbc:7) and saturated OVL.bad_flag (39|1, ovl.dbc:10) share bits"),
            std::string::npos)
      << error(f);
  // One signal in two roles (a review: these passed, as the same signal was never compared with itself).
  f.saturated = "OVL.cnt";
  EXPECT_NE(error(f).find("counter OVL.cnt (0|16, ovl.dbc:5) and saturated OVL.cnt (0|16, ovl.dbc:5) share bits"),
            std::string::npos)
      << error(f);
  f.saturated.clear();
  f.y = "OVL.x_ok";
  EXPECT_NE(error(f).find("x OVL.x_ok (16|24, ovl.dbc:7) and y OVL.x_ok (16|24, ovl.dbc:7) share bits"),
            std::string::npos)
      << error(f);
  f.y.clear();
  f.status = "OVL.cnt";
  f.saturated_bit = 0;
  EXPECT_NE(error(f).find("counter OVL.cnt (0|16, ovl.dbc:5) and status OVL.cnt"), std::string::npos) << error(f);
  DbcStreamSpec pages;
  pages.counter = "PAGES.cnt";
  pages.x = "PAGES.x";
  pages.y = "PAGES.y";
  EXPECT_EQ(error(pages), "no error");  // one page per frame: x and y never meet
  // A status word that also holds the counter (a review: refused, though only bits 0..2 are read).
  DbcStreamSpec word;
  word.counter = "WORD.cnt";
  word.x = "WORD.x";
  word.y = "WORD.y";
  word.status = "WORD.st";
  word.saturated_bit = 0;
  word.filter_on_bit = 1;
  word.loop_fault_bit = 2;
  EXPECT_EQ(error(word), "no error");
  word.loop_fault_bit = 8;  // the counter's lowest bit
  EXPECT_NE(error(word).find("counter WORD.cnt (40|8, ovl.dbc:20) and status WORD.st (32|16, ovl.dbc:19) share bits"),
            std::string::npos)
      << error(word);
}

TEST(DbcStream, HardwareFileDbcAndStreamTables) {
  const std::string text = "[dut]\ncan = \"vcan0\"\ndbc = \"" + kLayouts +
                           "\"\n[dut.stream]\ncounter = \"ACC_X.cnt\"\nx = \"ACC_X.x_counts\"\ny = \"ACC_Y.y_counts\"\n"
                           "status = \"ACC_X.st\"\nsaturated_bit = 0\nrate_hz = 2000\n";
  const toml::table t = cfg::parse_string(text, "hw.toml");
  const LinkOptions o = link_options(*t["dut"].as_table());
  ASSERT_TRUE(o.stream);
  EXPECT_EQ(o.stream->counter_bits(), 16);
  EXPECT_EQ(o.stream->rate_hz(), 2000.0);
  // Without dbc: the rig protocol's codec.
  EXPECT_FALSE(link_options(*cfg::parse_string("can = \"vcan0\"\n", "hw.toml").as_table()).stream);

  auto error = [](const std::string& txt) {
    try {
      SCOPED_TRACE(txt);
      const toml::table tt = cfg::parse_string(txt, "hw.toml");
      link_options(*tt["dut"].as_table());
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error("[dut]\ncan = \"vcan0\"\ndbc = \"" + kLayouts + "\"\n[dut.stream]\ncounter = \"ACC_X.cnt\"\nx = \"ACC_X.x\"\n"),
            "hw.toml:6:5: [dut.stream]: x = \"ACC_X.x\": no signal x in ACC_X");  // x's line, not the table's
  EXPECT_EQ(error("[dut]\ncan = \"vcan0\"\ndbc = \"" + kLayouts + "\"\n[dut.stream]\ncounter = \"ACC_X.cnt\"\nz = 1\n"),
            "hw.toml:6:1: unknown key 'z' in [dut.stream] (expected one of: counter, x, y, status, filter_on_bit, "
            "saturated_bit, loop_fault_bit, filter_on, saturated, loop_fault, samples_per_frame, rate_hz)");
  EXPECT_EQ(error("[dut]\ncan = \"vcan0\"\n[dut.stream]\nx = \"A.b\"\n"),
            "hw.toml:3:1: [dut.stream] needs [dut] dbc = \"FILE\"");
  EXPECT_EQ(error("[dut]\ncan = \"vcan0\"\ndbc = \"/nonexistent.dbc\"\n[dut.stream]\n"),
            "hw.toml:3:7: 'dbc' = '/nonexistent.dbc': no such file: /nonexistent.dbc");
  // A stream on the protocol's response id (0x011) would swallow the DUT's answers while the
  // link has a command channel (a review); without one the id is the stream's to use.
  const std::string dbc = testing::TempDir() + "/on-0x011.dbc";
  std::ofstream(dbc) << "VERSION \"\"\nBU_: DUT\nBO_ 17 S: 8 DUT\n SG_ cnt : 0|16@1+ (1,0) [0|65535] \"\" DUT\n"
                        " SG_ x : 16|32@1- (1e-06,0) [0|0] \"g\" DUT\n";
  const std::string on_rsp = "[dut]\ncan = \"vcan0\"\ndbc = \"" + dbc + "\"\n%s[dut.stream]\ncounter = \"S.cnt\"\nx = \"S.x\"\n";
  auto with = [&](const std::string& commands) {
    std::string t2 = on_rsp;
    t2.replace(t2.find("%s"), 2, commands);
    return t2;
  };
  EXPECT_EQ(error(with("")), "hw.toml:4:1: [dut.stream]: a stream message on CAN id 0x011, which the DUT protocol uses "
                             "for its responses ([dut] commands = true): move the stream or set commands = false");
  EXPECT_EQ(error(with("commands = false\n")), "no error");
}

// ---- through CanDutLink: the link's own guarantees (silence) for a DBC layout ---------

namespace {

// A DUT streaming ACC_XY frames at 1 kHz on the in-process bus, answering the rig
// protocol's START/STOP; `mute_after` samples it falls silent.
struct XyDut {
  std::unique_ptr<CanTransport> port;
  bool streaming = false;
  uint64_t k = 65000;
  uint64_t sent = 0, mute_after = ~uint64_t{0};
  double t = 0, next_t = 0;
  void step(double dt) {
    const CancelToken never;
    while (auto f = port->receive(0, never)) {
      const Decoded d = decode(f->frame);
      if (const auto* c = std::get_if<Command>(&d.msg)) {
        streaming = c->op == Op::StartStream ? true : c->op == Op::StopStream ? false : streaming;
        port->send(encode(Response{c->op, c->token, Result::Ok, 0, static_cast<uint32_t>(k)}));
      }
    }
    t += dt;
    while (streaming && next_t <= t) {
      if (sent < mute_after) {
        const CanFdFrame f = xy_frame(k);
        CanFrame c;
        c.id = f.id;
        c.extended = f.extended;
        c.len = f.len;
        std::copy_n(f.data.begin(), 8, c.data.begin());
        port->send(c);
        ++sent;
      }
      ++k;
      next_t += 1e-3;
    }
  }
};

}  // namespace

TEST(DbcStream, LinkReadsTheLayoutAndDeclaresSilence) {
  SimClock clock;  // the lockstep bus owns simulated time: its receive steps this clock
  InProcessBus::Options bo;
  bo.lockstep = &clock;
  auto bus = InProcessBus::create(bo);
  XyDut dut;
  dut.port = bus->open("dut");
  dut.mute_after = 900;
  clock.set_advance([&](double dt) { dut.step(dt); });
  LinkOptions o;
  o.stream = std::make_shared<const DbcStreamDecoder>(layouts(), xy_spec(), "test");
  CanDutLink link(bus->open("rig"), clock, o);
  link.start_stream({});
  std::vector<Sample> buf(800);
  ASSERT_EQ(link.read(buf, {}), 800u);
  for (std::size_t i = 1; i < buf.size(); ++i) ASSERT_EQ(buf[i].seq, buf[i - 1].seq + 1);  // across 65535 -> 65536
  EXPECT_GT(buf.back().seq, 65536u);
  EXPECT_NEAR(buf[0].x_g, x_of(buf[0].seq), 1e-6);
  try {
    link.read(buf, {});
    FAIL() << "expected silence";
  } catch (const HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("silent"), std::string::npos) << e.what();
  }
  EXPECT_EQ(link.stats().gaps, 0u);
  EXPECT_EQ(link.stats().received, 900u);
}
