// The DBC file (docs/rig-dut.dbc) is the protocol's public description: every
// message the codec produces must decode through it to the same values.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "firmware_link/candump_log.hpp"
#include "firmware_link/dbc.hpp"
#include "rig/core/errors.hpp"

using namespace rig::link;

namespace {

const Dbc& dbc() {
  static const Dbc d = Dbc::parse_file(std::string(RIG_SOURCE_DIR) + "/docs/rig-dut.dbc");
  return d;
}

std::map<std::string, double> signals(const CanFrame& f) {
  std::map<std::string, double> m;
  std::string err;
  const auto s = dbc().decode(f, &err);
  EXPECT_TRUE(s.has_value()) << to_candump(f) << " " << err;
  if (s)
    for (const auto& d : *s) m[d.name] = d.value;
  return m;
}

}  // namespace

TEST(Dbc, DefinesEveryProtocolMessageWithItsId) {
  const struct {
    uint32_t id;
    const char* name;
  } want[] = {{can_id::kCommand, "RIG_CMD"},
              {can_id::kResponse, "DUT_RSP"},
              {can_id::kStreamX, "DUT_STREAM_X"},
              {can_id::kStreamY, "DUT_STREAM_Y"},
              {can_id::kLoopData, "DUT_LOOP_DATA"},
              {can_id::kLoopEnd, "DUT_LOOP_END"},
              {can_id::kHeartbeat, "DUT_HEARTBEAT"}};
  ASSERT_EQ(dbc().messages().size(), std::size(want));
  for (const auto& w : want) {
    const DbcMessage* m = dbc().find(w.id);
    ASSERT_NE(m, nullptr) << w.name;
    EXPECT_EQ(m->name, w.name);
    EXPECT_EQ(m->dlc, 8);
  }
}

TEST(Dbc, OpcodeValueTableMatchesCodec) {
  const DbcSignal* op = dbc().find(can_id::kCommand)->signal("opcode");
  ASSERT_NE(op, nullptr);
  ASSERT_TRUE(op->multiplexor);
  int n = 0;
  for (int v = 0; v < 256; ++v) {
    const bool dbc_has = op->value_names.count(v) > 0;
    EXPECT_EQ(dbc_has, known_op(static_cast<uint8_t>(v))) << "opcode " << v;
    if (dbc_has) {
      EXPECT_EQ(op->value_names.at(v), to_string(static_cast<Op>(v)));
      ++n;
    }
  }
  EXPECT_EQ(n, 12);
}

TEST(Dbc, CommandsDecodeToCodecFields) {
  auto m = signals(encode(Command{Op::FilterCoef, 42, 2, 3, f32_bits(0.377156f)}));
  EXPECT_EQ(m.at("opcode"), 0x21);
  EXPECT_EQ(m.at("token"), 42);
  EXPECT_EQ(m.at("coef_section"), 2);
  EXPECT_EQ(m.at("coef_index"), 3);
  EXPECT_FLOAT_EQ(static_cast<float>(m.at("coef_value")), 0.377156f);
  EXPECT_EQ(m.count("begin_rate_hz"), 0u);  // other multiplexed signals are absent

  m = signals(encode(Command{Op::FilterBegin, 1, 2, 0, f32_bits(10000.0f)}));
  EXPECT_EQ(m.at("begin_sections"), 2);
  EXPECT_EQ(m.at("begin_rate_hz"), 10000.0);
  m = signals(encode(Command{Op::FilterGetCoef, 1, 5, 4, 0}));
  EXPECT_EQ(m.at("get_section"), 5);
  EXPECT_EQ(m.at("get_index"), 4);
  m = signals(encode(Command{Op::FilterEnable, 1, 1, 0, 0}));
  EXPECT_EQ(m.at("enable"), 1);
  m = signals(encode(Command{Op::GetSerial, 1, 3, 0, 0}));
  EXPECT_EQ(m.at("serial_chunk"), 3);
}

TEST(Dbc, ResponsesDecodeToCodecFields) {
  auto m = signals(encode(Response{Op::FilterGetInfo, 5, Result::Ok, 0x80 | 2, f32_bits(10000.0f)}));
  EXPECT_EQ(m.at("result"), 0);
  EXPECT_EQ(m.at("info_sections"), 2);
  EXPECT_EQ(m.at("info_enabled"), 1);
  EXPECT_EQ(m.at("info_rate_hz"), 10000.0);
  m = signals(encode(Response{Op::FilterGetCoef, 5, Result::Ok, 3 << 4 | 2, f32_bits(-1.5f)}));
  EXPECT_EQ(m.at("get_section"), 3);
  EXPECT_EQ(m.at("get_index"), 2);
  EXPECT_EQ(m.at("get_value"), -1.5);
  m = signals(encode(Response{Op::GetVersion, 5, Result::Ok, 1, 4u | 7u << 16}));
  EXPECT_EQ(m.at("fw_major"), 1);
  EXPECT_EQ(m.at("fw_minor"), 4);
  EXPECT_EQ(m.at("fw_patch"), 7);
  m = signals(encode(Response{Op::GetTemperature, 5, Result::Ok, 0, f32_bits(23.25f)}));
  EXPECT_EQ(m.at("temperature_c"), 23.25);
  m = signals(encode(Response{Op::StartStream, 5, Result::Ok, 0, 123456789u}));
  EXPECT_EQ(m.at("start_seq"), 123456789.0);
  m = signals(encode(Response{Op::GetSerial, 5, Result::Ok, 15, 0x2D415051u}));
  EXPECT_EQ(m.at("serial_length"), 15);
  EXPECT_EQ(m.at("serial_chars"), static_cast<double>(0x2D415051u));
  std::string err;
  const auto s = dbc().decode(encode(Response{Op::StopStream, 1, Result::BadState, 0, 0}), &err);
  ASSERT_TRUE(s);
  bool named = false;
  for (const auto& d : *s)
    if (d.name == "result") named = d.value_name == "BAD_STATE";
  EXPECT_TRUE(named);
}

TEST(Dbc, StreamAndHeartbeatDecodeToCodecFields) {
  auto m = signals(encode(StreamHalf{Channel::X, 0xABCDEF, stream_status::kFilterOn | stream_status::kLoopFault,
                                     -5.0137e-4f}));
  EXPECT_EQ(m.at("seq"), 0xABCDEF);
  EXPECT_EQ(m.at("status_filter_on"), 1);
  EXPECT_EQ(m.at("status_saturated"), 0);
  EXPECT_EQ(m.at("status_loop_fault"), 1);
  EXPECT_EQ(m.at("x_g"), static_cast<double>(-5.0137e-4f));
  m = signals(encode(StreamHalf{Channel::Y, 7, 0, 3.8549e-4f}));
  EXPECT_EQ(m.at("y_g"), static_cast<double>(3.8549e-4f));
  m = signals(encode(Heartbeat{hb_state::kStreaming, 77, -4.56, 4000000000u}));
  EXPECT_EQ(m.at("state_streaming"), 1);
  EXPECT_EQ(m.at("state_filter_on"), 0);
  EXPECT_EQ(m.at("hb_counter"), 77);
  EXPECT_NEAR(m.at("temperature_c"), -4.56, 1e-9);
  EXPECT_EQ(m.at("last_seq"), 4000000000.0);
}

TEST(Dbc, LoopTestCommandAndBurstDecodeToCodecFields) {
  auto m = signals(encode(Command{Op::LoopTest, 9, loop_cmd::kStep, 50, f32_bits(-1.0f)}));
  EXPECT_EQ(m.at("opcode"), 0x40);
  EXPECT_EQ(m.at("loop_kind"), 0);
  EXPECT_EQ(m.at("loop_record_ms"), 50);
  EXPECT_EQ(m.at("loop_amplitude_g"), -1.0);
  m = signals(encode(Response{Op::LoopTest, 9, Result::Ok, 0, 500}));
  EXPECT_EQ(m.at("loop_samples"), 500);
  m = signals(encode(LoopData{499, Channel::Y, 9, 0.998f}));
  EXPECT_EQ(m.at("loop_index"), 499);
  EXPECT_EQ(m.at("loop_channel"), 1);
  EXPECT_EQ(m.at("loop_token"), 9);
  EXPECT_EQ(m.at("loop_value_g"), static_cast<double>(0.998f));
  m = signals(encode(LoopEnd{9, loop_cmd::kAborted, 500, 50, 10000}));
  EXPECT_EQ(m.at("loop_token"), 9);
  EXPECT_EQ(m.at("loop_saturated"), 0);
  EXPECT_EQ(m.at("loop_aborted"), 1);
  EXPECT_EQ(m.at("loop_samples"), 500);
  EXPECT_EQ(m.at("loop_pre_samples"), 50);
  EXPECT_EQ(m.at("loop_rate_hz"), 10000);
}

TEST(Dbc, ParseErrorsNameFileAndLine) {
  try {
    Dbc::parse("VERSION \"\"\n\nBO_ 16 M: 8 RIG\n SG_ a : 60|8@1+ (1,0) [0|1] \"\" X\n", "bad.dbc");
    FAIL() << "expected ConfigError";
  } catch (const rig::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.dbc:4:"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Dbc::parse("BO_ 16 M: 1 RIG\n SG_ a : 0|8@0+ (1,0) [0|1] \"\" X\n", "motorola.dbc"), rig::ConfigError);
  EXPECT_THROW(Dbc::parse_file("/nonexistent.dbc"), rig::ConfigError);
}

TEST(Dbc, CandumpLogLines) {
  auto lf = parse_candump_line("(1732255200.123456) vcan0 101#563412050000803F");
  ASSERT_TRUE(lf);
  EXPECT_DOUBLE_EQ(lf->t_s, 1732255200.123456);
  EXPECT_EQ(lf->iface, "vcan0");
  EXPECT_EQ(lf->frame, encode(StreamHalf{Channel::Y, 0x123456, 5, 1.0f}));
  lf = parse_candump_line("010#3007010244332211");
  ASSERT_TRUE(lf);
  EXPECT_EQ(lf->frame, encode(Command{Op::GetSerial, 7, 1, 2, 0x11223344u}));
  lf = parse_candump_line("(1.0) can0 20000040#0000000000000000");
  ASSERT_TRUE(lf);
  EXPECT_TRUE(lf->frame.error);
  EXPECT_EQ(lf->frame.id, 0x40u);
  EXPECT_FALSE(parse_candump_line("# a comment"));
  EXPECT_FALSE(parse_candump_line("101#0102030"));  // odd number of hex digits
}

// Found by tests/fuzz (fuzz_dbc): numbers beyond their field's range ended the process with
// std::out_of_range from std::stoi; they are configuration errors naming the line.
TEST(Dbc, NumbersOutOfRangeAreErrorsNamingTheLine) {
  auto error = [](const std::string& text) {
    try {
      Dbc::parse(text, "t.dbc");
    } catch (const rig::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error("BO_ 256 X: 99999999999 DUT\n"), "t.dbc:1: DLC '99999999999' is not a whole number in range");
  EXPECT_EQ(error("BO_ 99999999999 X: 8 DUT\n"), "t.dbc:1: message id '99999999999' is not a whole number in range");
  EXPECT_EQ(error("BO_ 256 X: 8 DUT\n SG_ a : 99999999999|8@1+ (1,0) [0|1] \"\" Vector__XXX\n"),
            "t.dbc:2: start bit '99999999999' is not a whole number in range");
  EXPECT_EQ(error("BO_ 256 X: 8 DUT\n SG_ a : 0|8@1+ (1e999,0) [0|1] \"\" Vector__XXX\n"),
            "t.dbc:2: factor '1e999' is not a finite number");
}
