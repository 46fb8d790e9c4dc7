// The rig <-> DUT CAN protocol (docs/can-protocol.md, docs/rig-dut.dbc): frame
// identifiers, message layouts and the codec. Classic CAN 2.0A, 11-bit ids,
// all multi-byte fields little-endian, floats IEEE 754 binary32.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>

namespace rig::link {

// One classic CAN frame as it travels on the bus (SocketCAN's can_frame, minus padding).
struct CanFrame {
  uint32_t id = 0;  // 11-bit (or 29-bit when `extended`)
  uint8_t len = 0;  // 0..8
  std::array<uint8_t, 8> data{};
  bool extended = false;
  bool rtr = false;
  bool error = false;  // an error frame (SocketCAN CAN_ERR_FLAG); id holds the CAN_ERR_* class bits
};
bool operator==(const CanFrame& a, const CanFrame& b);

// A frame of any kind, CAN FD included (SocketCAN's canfd_frame: up to 64 data bytes):
// what DBC decoding and DBC-described streams take, from a log or an FD-capable
// transport. The classic codec above keeps CanFrame.
struct CanFdFrame {
  uint32_t id = 0;  // 11-bit (or 29-bit when `extended`)
  uint8_t len = 0;  // 0..8, 12, 16, 20, 24, 32, 48, 64
  std::array<uint8_t, 64> data{};
  bool extended = false;
  bool fd = false;   // sent as a CAN FD frame
  bool brs = false;  // CAN FD bit-rate switch
  bool rtr = false;
  bool error = false;
  static CanFdFrame from(const CanFrame& f);
};
// The CAN FD payload length a DLC code stands for, and the smallest valid FD length
// holding `bytes` (FD frames are padded to 12, 16, 20, 24, 32, 48 or 64 bytes).
int canfd_round_up(int bytes);

// Frame identifiers. Lower id = higher bus priority: commands beat the stream.
namespace can_id {
inline constexpr uint32_t kCommand = 0x010;    // rig -> DUT
inline constexpr uint32_t kResponse = 0x011;   // DUT -> rig, one per command
inline constexpr uint32_t kStreamX = 0x100;    // DUT -> rig, 1 kHz: seq24, status, x (g)
inline constexpr uint32_t kStreamY = 0x101;    // DUT -> rig, 1 kHz: seq24, status, y (g)
inline constexpr uint32_t kLoopData = 0x180;   // DUT -> rig, a loop test's burst: index, channel, token, value (g)
inline constexpr uint32_t kLoopEnd = 0x181;    // DUT -> rig, the burst's end marker
inline constexpr uint32_t kHeartbeat = 0x700;  // DUT -> rig, 10 Hz
}  // namespace can_id

enum class Op : uint8_t {
  StartStream = 0x01,
  StopStream = 0x02,
  FilterBegin = 0x20,    // a0 = number of sections (0..kMaxSections), value = rate_hz (f32)
  FilterCoef = 0x21,     // a0 = section, a1 = coefficient index (0..4 = b0 b1 b2 a1 a2), value = f32
  FilterCommit = 0x22,   // applies the staged filter (all coefficients must have been sent)
  FilterGetInfo = 0x23,  // -> aux = sections | enabled << 7, value = rate_hz (f32)
  FilterGetCoef = 0x24,  // a0 = section, a1 = index -> value = f32
  FilterEnable = 0x25,   // a0 = 0 off / 1 on
  GetSerial = 0x30,      // a0 = chunk -> aux = total length, value = 4 chars of chunk a0
  GetVersion = 0x31,     // -> aux = major, value = minor | patch << 16
  GetTemperature = 0x32, // -> value = degC (f32)
  LoopTest = 0x40,       // a0 = kind (0 = step), a1 = record ms, value = amplitude g (f32) -> value = samples per channel
};
const char* to_string(Op op);
bool known_op(uint8_t op);

enum class Result : uint8_t { Ok = 0, UnknownOp = 1, BadArgument = 2, BadState = 3 };
const char* to_string(Result r);

inline constexpr int kMaxSections = 8;
inline constexpr int kMaxSerial = 32;
// A serial the protocol can carry and every file can hold: 1..kMaxSerial printable ASCII
// characters (blanks inside only). "" when `s` is one, else why not.
inline std::string serial_problem(std::string_view s) {
  if (s.empty()) return "empty";
  if (s.size() > static_cast<std::size_t>(kMaxSerial))
    return std::to_string(s.size()) + " characters; a DUT reports at most " + std::to_string(kMaxSerial);
  for (const char c : s)
    if (c < 0x20 || c > 0x7E) return "not printable ASCII (the DUT protocol's serial is)";
  if (s.front() == ' ' || s.back() == ' ') return "starts or ends with a blank";
  return "";
}
inline constexpr uint32_t kSeqMask = 0xFFFFFF;  // the stream's sequence counter is 24 bits on the wire

// LOOP_TEST (docs/can-protocol.md "Loop test"): what the firmware accepts.
namespace loop_cmd {
inline constexpr uint8_t kStep = 0;            // a0: a step of test torque
inline constexpr uint8_t kMinRecordMs = 10;    // a1: record length, ms (0 = kDefaultRecordMs)
inline constexpr uint8_t kMaxRecordMs = 200;
inline constexpr uint8_t kDefaultRecordMs = 100;
inline constexpr float kMaxAmplitudeG = 5.0f;  // |value|: half the range, so the loop never saturates by design
// End marker status bits.
inline constexpr uint8_t kSaturated = 1u << 0;  // the loop saturated during the record (PWM duty or pick-off ADC)
inline constexpr uint8_t kAborted = 1u << 1;    // the test was cut short (power, stream start)
}  // namespace loop_cmd

// Stream status byte (the low 8 bits of rig::sample_status).
namespace stream_status {
inline constexpr uint8_t kFilterOn = 1u << 0;
inline constexpr uint8_t kSaturated = 1u << 1;
inline constexpr uint8_t kLoopFault = 1u << 2;
}  // namespace stream_status

// Heartbeat state byte.
namespace hb_state {
inline constexpr uint8_t kStreaming = 1u << 0;
inline constexpr uint8_t kFilterOn = 1u << 1;
inline constexpr uint8_t kFault = 1u << 2;
}  // namespace hb_state

// rig -> DUT: bytes op, token, a0, a1, value[4].
struct Command {
  Op op = Op::GetVersion;
  uint8_t token = 0;  // echoed in the response; tells a late answer from the current one
  uint8_t a0 = 0, a1 = 0;
  uint32_t value = 0;  // u32, or f32 bits (see f32_bits)
};
// DUT -> rig: bytes op, token, result, aux, value[4].
struct Response {
  Op op = Op::GetVersion;
  uint8_t token = 0;
  Result result = Result::Ok;
  uint8_t aux = 0;
  uint32_t value = 0;
};
// One half of a sample: x travels in kStreamX, y in kStreamY, both carry seq and status.
enum class Channel : uint8_t { X, Y };
struct StreamHalf {
  Channel channel = Channel::X;
  uint32_t seq24 = 0;
  uint8_t status = 0;
  float value_g = 0;
};
// One loop-rate value of a loop test's burst (kLoopData): sample `index` of the record,
// x (channel X, the loop's output) or y (channel Y, through the output filter).
struct LoopData {
  uint16_t index = 0;
  Channel channel = Channel::X;
  uint8_t token = 0;  // the LOOP_TEST command's token: a burst is never taken for another test's
  float value_g = 0;
};
// The burst's end marker (kLoopEnd): how many samples per channel were sent, how many of them
// precede the step, at what rate.
struct LoopEnd {
  uint8_t token = 0;
  uint8_t status = 0;  // loop_cmd::kSaturated | kAborted
  uint16_t samples = 0;
  uint16_t pre_samples = 0;
  uint16_t rate_hz = 0;
};
struct Heartbeat {
  uint8_t state = 0;
  uint8_t counter = 0;
  double temperature_c = 0;  // on the wire: int16, 0.01 degC
  uint32_t last_seq = 0;     // full 32-bit sample counter of the last sample produced
};

uint32_t f32_bits(float v);
float bits_f32(uint32_t u);

CanFrame encode(const Command& c);
CanFrame encode(const Response& r);
CanFrame encode(const StreamHalf& s);
CanFrame encode(const Heartbeat& h);
CanFrame encode(const LoopData& d);
CanFrame encode(const LoopEnd& e);

// Decodes any frame of the protocol. `msg` holds monostate for a frame that is
// not ours (other id) or malformed; then `error` says why if it was ours.
struct Decoded {
  std::variant<std::monostate, Command, Response, StreamHalf, Heartbeat, LoopData, LoopEnd> msg;
  std::string error;  // non-empty: one of our ids, but malformed (names id and the problem)
};
Decoded decode(const CanFrame& f);

// candump-style text: "010#0102030405060708".
std::string to_candump(const CanFrame& f);

}  // namespace rig::link
