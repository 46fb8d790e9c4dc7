#include "firmware_link/protocol.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <limits>

namespace rig::link {

namespace {

void put_u32(std::array<uint8_t, 8>& d, int at, uint32_t v) {
  for (int i = 0; i < 4; ++i) d[static_cast<std::size_t>(at + i)] = static_cast<uint8_t>(v >> (8 * i));
}
uint32_t get_u32(const std::array<uint8_t, 8>& d, int at) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(d[static_cast<std::size_t>(at + i)]) << (8 * i);
  return v;
}

std::string malformed(uint32_t id, const char* what, unsigned len, unsigned want) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "frame 0x%03X (%s): length %u, expected %u", id, what, len, want);
  return buf;
}

}  // namespace

bool operator==(const CanFrame& a, const CanFrame& b) {
  if (a.id != b.id || a.len != b.len || a.extended != b.extended || a.rtr != b.rtr || a.error != b.error) return false;
  for (unsigned i = 0; i < a.len && i < 8; ++i)
    if (a.data[i] != b.data[i]) return false;
  return true;
}

CanFdFrame CanFdFrame::from(const CanFrame& f) {
  CanFdFrame o;
  o.id = f.id;
  o.len = f.len > 8 ? 8 : f.len;
  for (unsigned i = 0; i < o.len; ++i) o.data[i] = f.data[i];
  o.extended = f.extended;
  o.rtr = f.rtr;
  o.error = f.error;
  return o;
}

int canfd_round_up(int bytes) {
  if (bytes <= 8) return bytes < 0 ? 0 : bytes;
  for (int l : {12, 16, 20, 24, 32, 48, 64})
    if (bytes <= l) return l;
  return -1;
}

const char* to_string(Op op) {
  switch (op) {
    case Op::StartStream: return "START_STREAM";
    case Op::StopStream: return "STOP_STREAM";
    case Op::FilterBegin: return "FILTER_BEGIN";
    case Op::FilterCoef: return "FILTER_COEF";
    case Op::FilterCommit: return "FILTER_COMMIT";
    case Op::FilterGetInfo: return "FILTER_GET_INFO";
    case Op::FilterGetCoef: return "FILTER_GET_COEF";
    case Op::FilterEnable: return "FILTER_ENABLE";
    case Op::GetSerial: return "GET_SERIAL";
    case Op::GetVersion: return "GET_VERSION";
    case Op::GetTemperature: return "GET_TEMPERATURE";
    case Op::LoopTest: return "LOOP_TEST";
  }
  return "UNKNOWN_OP";
}

bool known_op(uint8_t op) {
  switch (static_cast<Op>(op)) {
    case Op::StartStream:
    case Op::StopStream:
    case Op::FilterBegin:
    case Op::FilterCoef:
    case Op::FilterCommit:
    case Op::FilterGetInfo:
    case Op::FilterGetCoef:
    case Op::FilterEnable:
    case Op::GetSerial:
    case Op::GetVersion:
    case Op::GetTemperature:
    case Op::LoopTest: return true;
  }
  return false;
}

const char* to_string(Result r) {
  switch (r) {
    case Result::Ok: return "OK";
    case Result::UnknownOp: return "UNKNOWN_OP";
    case Result::BadArgument: return "BAD_ARGUMENT";
    case Result::BadState: return "BAD_STATE";
  }
  return "?";
}

uint32_t f32_bits(float v) { return std::bit_cast<uint32_t>(v); }
float bits_f32(uint32_t u) { return std::bit_cast<float>(u); }

CanFrame encode(const Command& c) {
  CanFrame f;
  f.id = can_id::kCommand;
  f.len = 8;
  f.data[0] = static_cast<uint8_t>(c.op);
  f.data[1] = c.token;
  f.data[2] = c.a0;
  f.data[3] = c.a1;
  put_u32(f.data, 4, c.value);
  return f;
}

CanFrame encode(const Response& r) {
  CanFrame f;
  f.id = can_id::kResponse;
  f.len = 8;
  f.data[0] = static_cast<uint8_t>(r.op);
  f.data[1] = r.token;
  f.data[2] = static_cast<uint8_t>(r.result);
  f.data[3] = r.aux;
  put_u32(f.data, 4, r.value);
  return f;
}

CanFrame encode(const StreamHalf& s) {
  CanFrame f;
  f.id = s.channel == Channel::X ? can_id::kStreamX : can_id::kStreamY;
  f.len = 8;
  const uint32_t seq = s.seq24 & kSeqMask;
  f.data[0] = static_cast<uint8_t>(seq);
  f.data[1] = static_cast<uint8_t>(seq >> 8);
  f.data[2] = static_cast<uint8_t>(seq >> 16);
  f.data[3] = s.status;
  put_u32(f.data, 4, f32_bits(s.value_g));
  return f;
}

CanFrame encode(const Heartbeat& h) {
  CanFrame f;
  f.id = can_id::kHeartbeat;
  f.len = 8;
  f.data[0] = h.state;
  f.data[1] = h.counter;
  // int16 in 0.01 degC, saturated to the field's range.
  const double t = std::clamp(std::round(h.temperature_c * 100.0), -32768.0, 32767.0);
  const auto t16 = static_cast<uint16_t>(static_cast<int16_t>(t));
  f.data[2] = static_cast<uint8_t>(t16);
  f.data[3] = static_cast<uint8_t>(t16 >> 8);
  put_u32(f.data, 4, h.last_seq);
  return f;
}

CanFrame encode(const LoopData& d) {
  CanFrame f;
  f.id = can_id::kLoopData;
  f.len = 8;
  f.data[0] = static_cast<uint8_t>(d.index);
  f.data[1] = static_cast<uint8_t>(d.index >> 8);
  f.data[2] = d.channel == Channel::X ? 0 : 1;
  f.data[3] = d.token;
  put_u32(f.data, 4, f32_bits(d.value_g));
  return f;
}

CanFrame encode(const LoopEnd& e) {
  CanFrame f;
  f.id = can_id::kLoopEnd;
  f.len = 8;
  f.data[0] = e.token;
  f.data[1] = e.status;
  f.data[2] = static_cast<uint8_t>(e.samples);
  f.data[3] = static_cast<uint8_t>(e.samples >> 8);
  f.data[4] = static_cast<uint8_t>(e.pre_samples);
  f.data[5] = static_cast<uint8_t>(e.pre_samples >> 8);
  f.data[6] = static_cast<uint8_t>(e.rate_hz);
  f.data[7] = static_cast<uint8_t>(e.rate_hz >> 8);
  return f;
}

Decoded decode(const CanFrame& f) {
  Decoded d;
  if (f.error || f.rtr || f.extended) return d;
  switch (f.id) {
    case can_id::kCommand: {
      if (f.len != 8) return {{}, malformed(f.id, "RIG_CMD", f.len, 8)};
      Command c;
      c.op = static_cast<Op>(f.data[0]);
      c.token = f.data[1];
      c.a0 = f.data[2];
      c.a1 = f.data[3];
      c.value = get_u32(f.data, 4);
      d.msg = c;
      return d;
    }
    case can_id::kResponse: {
      if (f.len != 8) return {{}, malformed(f.id, "DUT_RSP", f.len, 8)};
      Response r;
      r.op = static_cast<Op>(f.data[0]);
      r.token = f.data[1];
      r.result = static_cast<Result>(f.data[2]);
      r.aux = f.data[3];
      r.value = get_u32(f.data, 4);
      d.msg = r;
      return d;
    }
    case can_id::kStreamX:
    case can_id::kStreamY: {
      if (f.len != 8) return {{}, malformed(f.id, f.id == can_id::kStreamX ? "DUT_STREAM_X" : "DUT_STREAM_Y", f.len, 8)};
      StreamHalf s;
      s.channel = f.id == can_id::kStreamX ? Channel::X : Channel::Y;
      s.seq24 = static_cast<uint32_t>(f.data[0]) | static_cast<uint32_t>(f.data[1]) << 8 |
                static_cast<uint32_t>(f.data[2]) << 16;
      s.status = f.data[3];
      s.value_g = bits_f32(get_u32(f.data, 4));
      d.msg = s;
      return d;
    }
    case can_id::kHeartbeat: {
      if (f.len != 8) return {{}, malformed(f.id, "DUT_HEARTBEAT", f.len, 8)};
      Heartbeat h;
      h.state = f.data[0];
      h.counter = f.data[1];
      const auto t16 = static_cast<int16_t>(static_cast<uint16_t>(f.data[2] | f.data[3] << 8));
      h.temperature_c = t16 / 100.0;
      h.last_seq = get_u32(f.data, 4);
      d.msg = h;
      return d;
    }
    case can_id::kLoopData: {
      if (f.len != 8) return {{}, malformed(f.id, "DUT_LOOP_DATA", f.len, 8)};
      if (f.data[2] > 1) return {{}, "frame 0x180 (DUT_LOOP_DATA): channel " + std::to_string(f.data[2]) + ", expected 0 or 1"};
      LoopData l;
      l.index = static_cast<uint16_t>(f.data[0] | f.data[1] << 8);
      l.channel = f.data[2] == 0 ? Channel::X : Channel::Y;
      l.token = f.data[3];
      l.value_g = bits_f32(get_u32(f.data, 4));
      d.msg = l;
      return d;
    }
    case can_id::kLoopEnd: {
      if (f.len != 8) return {{}, malformed(f.id, "DUT_LOOP_END", f.len, 8)};
      LoopEnd e;
      e.token = f.data[0];
      e.status = f.data[1];
      e.samples = static_cast<uint16_t>(f.data[2] | f.data[3] << 8);
      e.pre_samples = static_cast<uint16_t>(f.data[4] | f.data[5] << 8);
      e.rate_hz = static_cast<uint16_t>(f.data[6] | f.data[7] << 8);
      d.msg = e;
      return d;
    }
    default: return d;
  }
}

std::string to_candump(const CanFrame& f) {
  char buf[64];
  int n = f.extended ? std::snprintf(buf, sizeof buf, "%08X#", f.id) : std::snprintf(buf, sizeof buf, "%03X#", f.id);
  for (unsigned i = 0; i < f.len && i < 8; ++i) n += std::snprintf(buf + n, sizeof buf - static_cast<std::size_t>(n), "%02X", f.data[i]);
  return std::string(buf, static_cast<std::size_t>(n));
}

}  // namespace rig::link
