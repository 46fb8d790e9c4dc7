// A DUT stream described by a DBC: which signals carry the sample counter, x, y and the
// status, and the decoder that turns the stream's frames into the reassembly's input
// (StreamPart), so that widening, the reorder window, located gaps, duplicates and
// silence work for any layout exactly as for the rig protocol (docs/can-protocol.md,
// "DBC-described streams"; docs/hardware-config.md, [dut.stream]).
//
// Signals are named "MESSAGE.SIGNAL". A sample may span several frames (x in one
// message, y in another, as the rig protocol does): every message that carries part of
// a sample carries the counter, under the same signal name as in the message `counter`
// names (so do the status and flag signals, where a message has them). Several samples
// may travel in one frame (CAN FD): with samples_per_frame = N, the x, y, status and
// flag names are prefixes of per-sample signals x0..x(N-1) (a status or flag signal
// without an index applies to every sample of the frame), and the counter is sample 0's:
// sample i has counter + i.
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include "firmware_link/can_transport.hpp"
#include "firmware_link/dbc.hpp"
#include "firmware_link/reassembly.hpp"

namespace rig::link {

// [dut.stream] as written: signal names, status bit numbers, layout.
struct DbcStreamSpec {
  std::string counter, x, y, status;
  // Bits of `status` (its raw value) that mean filter on / saturated / loop fault; -1: none.
  int filter_on_bit = -1, saturated_bit = -1, loop_fault_bit = -1;
  // One-bit (or any: nonzero = set) signals for the same flags, as an alternative.
  std::string filter_on, saturated, loop_fault;
  int samples_per_frame = 1;
  double rate_hz = 1000;  // samples per second (the capture header's rate)
  // The rig protocol is classic CAN (docs/can-protocol.md): an FD frame on its ids is another
  // node's, in a log as on the link (can_dut_link.cpp). A DBC's stream takes both.
  bool classic_only = false;
  // Where each key was written ("hw.toml:19:5: [dut.stream]"), for the decoder's messages: an
  // error about `y` names y's line, not the table's (a review). Keys absent here: `where`.
  std::map<std::string, std::string> key_where;
};

class DbcStreamDecoder {
 public:
  // Resolves the spec against the DBC; a name that does not resolve, a counter that is
  // not an integer, a unit that is not an acceleration => ConfigError prefixed `where`.
  DbcStreamDecoder(std::shared_ptr<const Dbc> dbc, DbcStreamSpec spec, const std::string& where);

  // Appends the parts a frame carries. Returns false for a frame that is not one of the
  // stream's messages. A stream frame of the wrong length (or whose multiplexer selects
  // no counter) carries nothing; `error` then says why (empty when the frame is fine).
  bool decode(const CanFdFrame& f, std::vector<StreamPart>& out, std::string* error = nullptr) const;
  bool decode(const CanFrame& f, std::vector<StreamPart>& out, std::string* error = nullptr) const {
    return decode(CanFdFrame::from(f), out, error);
  }

  int counter_bits() const { return counter_bits_; }
  // The factor from a channel's signal unit to g (mg: 1e-3): value_g / it is the DBC's value.
  double scale_to_g(Channel c) const { return c == Channel::X ? x_scale_ : y_scale_; }
  bool has_y() const { return !spec_.y.empty(); }
  double rate_hz() const { return spec_.rate_hz; }
  const DbcStreamSpec& spec() const { return spec_; }
  const Dbc& dbc() const { return *dbc_; }
  // Receive filters selecting the stream's frames (exact ids).
  std::vector<CanFilter> filters() const;
  // A reassembler sized for this stream (counter width, with or without y).
  // hold_start: for a log's import (StreamReassembler).
  StreamReassembler make_reassembler(uint32_t window, bool hold_start = false) const {
    return StreamReassembler(window, counter_bits_, has_y(), hold_start);
  }

 private:
  friend class DbcStreamEncoder;  // the inverse walks the same resolved layout
  struct Slot {  // one role of one sample within a message
    const DbcSignal* x = nullptr;
    const DbcSignal* y = nullptr;
    const DbcSignal* status = nullptr;
    const DbcSignal* flag[3] = {nullptr, nullptr, nullptr};  // filter on, saturated, loop fault
  };
  struct Roles {
    const DbcMessage* msg = nullptr;
    const DbcSignal* counter = nullptr;
    std::vector<Slot> samples;  // samples_per_frame entries
  };
  static uint64_t key(uint32_t id, bool extended) { return (uint64_t{extended} << 32) | id; }

  std::shared_ptr<const Dbc> dbc_;
  DbcStreamSpec spec_;
  int counter_bits_ = 0;
  double x_scale_ = 1, y_scale_ = 1;  // the signals' unit to g
  std::map<uint64_t, Roles> by_frame_;
};

// The inverse of the decoder, for emulated firmware and tests (never the rig's receive path):
// the frames a DUT streaming this layout sends. Built on the decoder's resolved layout, so the
// two cannot disagree on a signal's place, byte order, scale or multiplexer value.
struct StreamSample {
  float x_g = 0, y_g = 0;
  uint8_t status = 0;  // stream_status bits (filter on, saturated, loop fault)
};
class DbcStreamEncoder {
 public:
  // A layout whose messages cannot be sent (a multiplexed counter with a role under another
  // multiplexer value) => ConfigError. Roles under several values are sent as one frame per
  // value, in the value's order.
  explicit DbcStreamEncoder(std::shared_ptr<const DbcStreamDecoder> layout);
  int samples_per_frame() const { return layout_->spec().samples_per_frame; }
  // Whether any frame is longer than 8 bytes (a CAN FD layout).
  bool fd() const { return fd_; }
  // The frames of samples_per_frame() samples, the first with `counter` (its low counter_bits
  // are sent; sample i has counter + i), one frame per message of the layout in identifier
  // order (per multiplexer value of a multiplexed one). Values beyond an integer signal's range are sent as its end value (a saturated
  // output stays saturated); a status or flag signal shared by the samples of a frame carries
  // the OR of their flags.
  void encode(uint32_t counter, std::span<const StreamSample> samples, std::vector<CanFdFrame>& out) const;
  const std::shared_ptr<const DbcStreamDecoder>& layout() const { return layout_; }

 private:
  // One frame of message `r`: the roles under multiplexer value `page` (none: not multiplexed).
  void encode_page(const DbcStreamDecoder::Roles& r, std::optional<int> page, uint32_t counter,
                   std::span<const StreamSample> samples, uint8_t all, std::vector<CanFdFrame>& out) const;

  std::shared_ptr<const DbcStreamDecoder> layout_;
  std::map<uint64_t, std::vector<int>> pages_;  // per message: the multiplexer values its frames carry
  bool fd_ = false;
};

// The rig protocol (docs/rig-dut.dbc, built into the program) and its stream section.
std::shared_ptr<const Dbc> rig_protocol_dbc();
DbcStreamSpec rig_protocol_stream();

// [dut] dbc = "FILE" (relative to the hardware file's folder) and [dut.stream]; unknown
// keys and bad values => ConfigError naming file:line. Without `dbc`: the rig protocol's
// DBC and stream (then [dut.stream] may not be given). `section`: the table's name in messages
// ("plant.firmware" for the emulated firmware's, spelled the same).
std::shared_ptr<const DbcStreamDecoder> stream_decoder_from_config(const toml::table& dut,
                                                                   const std::string& section = "dut");
// [dut] dbc's path as stream_decoder_from_config() reads it (relative to the hardware file's
// folder); empty without `dbc`.
std::string dut_dbc_path(const toml::table& dut);

}  // namespace rig::link
