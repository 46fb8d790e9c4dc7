// A reader for the subset of the DBC format docs/rig-dut.dbc uses (BO_, SG_ with
// simple multiplexing, VAL_, SIG_VALTYPE_), and a signal decoder driven by it.
// cantools is not packaged for Debian 12, so the candump logs of the kernel
// tests are decoded with this (tests/kernel, `rig dut decode`).
#pragma once
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "firmware_link/protocol.hpp"

namespace rig::link {

struct DbcSignal {
  std::string name;
  int start = 0, length = 0;  // Intel (little-endian) bit numbering
  bool is_signed = false;
  int value_type = 0;  // 0 integer, 1 IEEE float32, 2 IEEE float64 (SIG_VALTYPE_)
  double factor = 1, offset = 0, min = 0, max = 0;
  std::string unit;
  bool multiplexor = false;        // "M"
  std::optional<int> mux_value;    // "mN": present only when the multiplexor equals N
  std::map<int64_t, std::string> value_names;  // VAL_
  int line = 0;                    // where it is defined
};

struct DbcMessage {
  uint32_t id = 0;
  std::string name;
  int dlc = 0;
  std::string sender;
  std::vector<DbcSignal> signals;
  const DbcSignal* signal(const std::string& name) const;
};

struct DecodedSignal {
  std::string name;
  double value = 0;
  std::string unit;
  std::string value_name;  // from VAL_, if any
};

class Dbc {
 public:
  // Syntax errors and unsupported features => ConfigError("file:line: ...").
  static Dbc parse_file(const std::string& path);
  static Dbc parse(const std::string& text, const std::string& source_name);

  const std::vector<DbcMessage>& messages() const { return messages_; }
  const DbcMessage* find(uint32_t id) const;
  // Decodes a frame of a known message: the signals present (multiplexing
  // applied), in definition order. nullopt for an unknown id. A length that
  // does not match the message's DLC => ConfigError-free std::nullopt + `error`.
  std::optional<std::vector<DecodedSignal>> decode(const CanFrame& f, std::string* error = nullptr) const;

 private:
  std::vector<DbcMessage> messages_;
};

// Raw value of a signal (Intel byte order), before factor/offset.
uint64_t dbc_extract_raw(const CanFrame& f, int start, int length);
double dbc_physical(const DbcSignal& s, const CanFrame& f);

// Reading candump logs (LoggedFrame, parse_candump_line) is firmware_link/candump_log.hpp.

}  // namespace rig::link
