#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "firmware_link/protocol.hpp"

using namespace rig::link;

TEST(Protocol, CommandRoundTrip) {
  const Command c{Op::FilterCoef, 0xA5, 3, 4, f32_bits(-1.228261f)};
  const CanFrame f = encode(c);
  EXPECT_EQ(f.id, can_id::kCommand);
  EXPECT_EQ(f.len, 8);
  EXPECT_EQ(to_candump(f).substr(0, 12), "010#21A50304");
  const Decoded d = decode(f);
  ASSERT_TRUE(d.error.empty());
  const auto* r = std::get_if<Command>(&d.msg);
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->op, Op::FilterCoef);
  EXPECT_EQ(r->token, 0xA5);
  EXPECT_EQ(r->a0, 3);
  EXPECT_EQ(r->a1, 4);
  EXPECT_EQ(bits_f32(r->value), -1.228261f);
}

TEST(Protocol, WireLayoutIsLittleEndian) {
  // value 0x11223344 must travel as 44 33 22 11 in bytes 4..7.
  const CanFrame f = encode(Command{Op::GetSerial, 7, 1, 2, 0x11223344u});
  EXPECT_EQ(to_candump(f), "010#3007010244332211");
  const CanFrame s = encode(StreamHalf{Channel::Y, 0x123456, 0x05, 1.0f});
  EXPECT_EQ(to_candump(s), "101#563412050000803F");  // 1.0f = 0x3F800000
}

TEST(Protocol, ResponseRoundTrip) {
  const Response r{Op::GetVersion, 9, Result::BadState, 0x81, 0xDEADBEEF};
  const Decoded d = decode(encode(r));
  const auto* p = std::get_if<Response>(&d.msg);
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->op, Op::GetVersion);
  EXPECT_EQ(p->token, 9);
  EXPECT_EQ(p->result, Result::BadState);
  EXPECT_EQ(p->aux, 0x81);
  EXPECT_EQ(p->value, 0xDEADBEEFu);
}

TEST(Protocol, StreamHalvesCarry24BitSeqStatusAndExactFloat) {
  for (float v : {0.0f, -5.0137e-4f, 3.8549e-4f, 9.999f, -10.0f, std::numeric_limits<float>::denorm_min()}) {
    for (uint32_t seq : {0u, 1u, 0xFFFFFFu, 0x1000000u /* wraps to 0 */}) {
      const CanFrame f = encode(StreamHalf{Channel::X, seq, stream_status::kFilterOn, v});
      EXPECT_EQ(f.id, can_id::kStreamX);
      const Decoded d = decode(f);
      const auto* s = std::get_if<StreamHalf>(&d.msg);
      ASSERT_NE(s, nullptr);
      EXPECT_EQ(s->channel, Channel::X);
      EXPECT_EQ(s->seq24, seq & kSeqMask);
      EXPECT_EQ(s->status, stream_status::kFilterOn);
      EXPECT_EQ(f32_bits(s->value_g), f32_bits(v));  // bit-exact
    }
  }
}

TEST(Protocol, HeartbeatTemperatureIsCentidegreesSaturated) {
  Heartbeat h{hb_state::kStreaming | hb_state::kFilterOn, 200, -12.345, 0xFFFFFFFEu};
  Decoded dec = decode(encode(h));
  auto* d = std::get_if<Heartbeat>(&dec.msg);
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(d->state, hb_state::kStreaming | hb_state::kFilterOn);
  EXPECT_EQ(d->counter, 200);
  EXPECT_DOUBLE_EQ(d->temperature_c, -12.35);  // rounded to 0.01 degC (-1234.5 rounds away from zero)
  EXPECT_EQ(d->last_seq, 0xFFFFFFFEu);
  h.temperature_c = 1000.0;  // beyond int16 centidegrees
  dec = decode(encode(h));
  d = std::get_if<Heartbeat>(&dec.msg);
  ASSERT_NE(d, nullptr);
  EXPECT_DOUBLE_EQ(d->temperature_c, 327.67);
}

TEST(Protocol, MalformedAndForeignFrames) {
  CanFrame f = encode(StreamHalf{Channel::Y, 1, 0, 1.0f});
  f.len = 6;
  const Decoded d = decode(f);
  EXPECT_TRUE(std::holds_alternative<std::monostate>(d.msg));
  EXPECT_NE(d.error.find("0x101"), std::string::npos) << d.error;
  EXPECT_NE(d.error.find("length 6"), std::string::npos) << d.error;

  CanFrame other;
  other.id = 0x321;
  other.len = 2;
  const Decoded o = decode(other);
  EXPECT_TRUE(std::holds_alternative<std::monostate>(o.msg));
  EXPECT_TRUE(o.error.empty());

  CanFrame ext = encode(Command{});
  ext.extended = true;  // same numeric id, but a 29-bit frame is not ours
  EXPECT_TRUE(std::holds_alternative<std::monostate>(decode(ext).msg));
}

TEST(Protocol, OpNamesAndKnownOps) {
  EXPECT_STREQ(to_string(Op::FilterGetInfo), "FILTER_GET_INFO");
  EXPECT_TRUE(known_op(0x25));
  EXPECT_FALSE(known_op(0x26));
  EXPECT_FALSE(known_op(0x00));
  EXPECT_STREQ(to_string(Result::BadArgument), "BAD_ARGUMENT");
}

TEST(Protocol, BusLoadAt1kHzIsUnderHalf) {
  // Worst-case classic CAN 2.0A frame with 8 data bytes: 111 bits + at most 24
  // stuff bits (ISO 11898-1: stuffing covers SOF..CRC = 98 bits, one stuff bit
  // per 4 after the first 5) = 135 bits. Two stream frames per ms plus a
  // heartbeat every 100 ms at 1 Mbit/s:
  const double bits_per_s = 2 * 135 * 1000.0 + 135 * 10.0;
  EXPECT_LT(bits_per_s / 1e6, 0.5);
  EXPECT_NEAR(bits_per_s / 1e6, 0.2714, 1e-4);
}
