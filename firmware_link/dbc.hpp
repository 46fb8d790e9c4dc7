// A reader for DBC files as CAN tools write them (Vector CANdb++, canmatrix, cantools):
// VERSION, NS_, BS_, BU_, BO_ (standard and extended ids, classic and CAN FD payloads up
// to 64 bytes), SG_ (Intel and Motorola byte order, signed, scale/offset, simple
// multiplexing M / mN), CM_, VAL_TABLE_, VAL_, BA_DEF_ / BA_DEF_DEF_ / BA_ (and their
// _REL_ forms), SIG_GROUP_, SIG_VALTYPE_, BO_TX_BU_; the remaining statements of the
// format (EV_, ENVVAR_DATA_, SGTYPE_, SIG_TYPE_REF_, SG_MUL_VAL_, CAT_, FILTER ...) are
// read to their ';' and skipped. Statements ending in ';' may span lines (comments
// often do). A malformed file is a ConfigError naming file:line.
// cantools is not packaged for Debian 12, so the candump logs of the kernel tests are
// decoded with this (tests/kernel, `rig dut decode`), and DBC-described DUT streams
// (firmware_link/dbc_stream.hpp) are decoded through it.
#pragma once
#include <bitset>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "firmware_link/protocol.hpp"

namespace rig::link {

// Attribute values as written (numbers as text, strings unquoted, an ENUM's index
// replaced by its name).
using DbcAttributes = std::map<std::string, std::string>;

struct DbcSignal {
  std::string name;
  int start = 0, length = 0;  // DBC bit numbering: Intel = LSB's bit, Motorola = MSB's bit
  bool big_endian = false;    // "@0" (Motorola); "@1" is Intel (little-endian)
  bool is_signed = false;
  int value_type = 0;  // 0 integer, 1 IEEE float32, 2 IEEE float64 (SIG_VALTYPE_)
  double factor = 1, offset = 0, min = 0, max = 0;
  std::string unit;
  bool multiplexor = false;        // "M"
  std::optional<int> mux_value;    // "mN": present only when the multiplexor equals N
  std::map<int64_t, std::string> value_names;  // VAL_
  std::vector<std::string> receivers;
  std::string comment;             // CM_ SG_
  DbcAttributes attributes;        // BA_ ... SG_
  int line = 0;                    // where it is defined
};

struct DbcSignalGroup {
  std::string name;
  int repetitions = 1;
  std::vector<std::string> signals;
};

struct DbcMessage {
  uint32_t id = 0;        // 11 or 29 bits, without the DBC's bit-31 marker
  bool extended = false;  // BO_ id had bit 31 set
  std::string name;
  int dlc = 0;            // payload bytes, 0..64 (more than 8: a CAN FD frame)
  std::string sender;
  std::vector<std::string> transmitters;  // BO_TX_BU_
  std::vector<DbcSignal> signals;
  std::vector<DbcSignalGroup> groups;     // SIG_GROUP_
  std::string comment;                    // CM_ BO_
  DbcAttributes attributes;               // BA_ ... BO_
  int line = 0;
  const DbcSignal* signal(const std::string& name) const;
};

struct DbcAttributeDefinition {
  std::string name;
  std::string object;  // "" (database), "BU_", "BO_", "SG_", "EV_", "BU_SG_REL_", ...
  std::string type;    // INT, HEX, FLOAT, STRING, ENUM
  std::vector<std::string> enum_values;
  std::string default_value;  // BA_DEF_DEF_ (as written)
};

struct DecodedSignal {
  std::string name;
  double value = 0;
  std::string unit;
  std::string value_name;  // from VAL_, if any
  uint64_t raw = 0;        // the signal's bits before factor and offset (dbc_physical_exact reads them)
};

class Dbc {
 public:
  // Syntax errors and unsupported features => ConfigError("file:line: ...").
  static Dbc parse_file(const std::string& path);
  static Dbc parse(const std::string& text, const std::string& source_name);

  const std::vector<DbcMessage>& messages() const { return messages_; }
  // Exact lookup by id and kind of identifier.
  const DbcMessage* find(uint32_t id, bool extended) const;
  // The standard-id message `id`, or else the extended-id one (ids of the two kinds
  // rarely collide; use the two-argument form where they can).
  const DbcMessage* find(uint32_t id) const;
  const DbcMessage* find(const std::string& name) const;
  // Decodes a frame of a known message: the signals present (multiplexing
  // applied), in definition order. nullopt for an unknown id. A length that
  // does not match the message's DLC => std::nullopt + `error`.
  std::optional<std::vector<DecodedSignal>> decode(const CanFrame& f, std::string* error = nullptr) const;
  std::optional<std::vector<DecodedSignal>> decode(const CanFdFrame& f, std::string* error = nullptr) const;

  // The file it was read from, as given (or parse()'s source name): messages about a signal
  // name it with the signal's line, "FILE:LINE".
  const std::string& source() const { return source_; }
  const std::string& version() const { return version_; }
  const std::vector<std::string>& nodes() const { return nodes_; }
  const std::string& comment() const { return comment_; }
  const std::map<std::string, std::string>& node_comments() const { return node_comments_; }
  const std::map<std::string, std::map<int64_t, std::string>>& value_tables() const { return value_tables_; }
  const std::map<std::string, DbcAttributeDefinition>& attribute_definitions() const { return attr_defs_; }
  const DbcAttributes& attributes() const { return attributes_; }                     // database-level BA_
  const std::map<std::string, DbcAttributes>& node_attributes() const { return node_attributes_; }
  // The value of an attribute on an object, else its BA_DEF_DEF_ default, else nullopt.
  std::optional<std::string> attribute(const DbcAttributes& on, const std::string& name) const;

 private:
  friend class DbcParser;
  std::vector<DbcMessage> messages_;
  std::string source_, version_, comment_;
  std::vector<std::string> nodes_;
  std::map<std::string, std::string> node_comments_;
  std::map<std::string, std::map<int64_t, std::string>> value_tables_;
  std::map<std::string, DbcAttributeDefinition> attr_defs_;
  DbcAttributes attributes_;
  std::map<std::string, DbcAttributes> node_attributes_;
};

// Raw value of a signal before factor/offset: Intel byte order in a classic frame (the
// original interface), and either byte order in any payload (up to 64 bytes).
uint64_t dbc_extract_raw(const CanFrame& f, int start, int length);
uint64_t dbc_extract_raw(std::span<const uint8_t> payload, int start, int length, bool big_endian);
// The inverse (tests, emulators): writes the low `length` bits of `raw` into the payload.
void dbc_insert_raw(std::span<uint8_t> payload, int start, int length, bool big_endian, uint64_t raw);
// Physical value: raw as integer (signed or not) or IEEE float, then factor and offset.
double dbc_physical(const DbcSignal& s, const CanFrame& f);
double dbc_physical(const DbcSignal& s, std::span<const uint8_t> payload);
// The physical value of the raw bits `raw` in decimal, exactly, where a double may not hold it: an
// integer signal whose factor and offset are whole numbers below 2^53 (raw * factor + offset in
// 128-bit integers; a 64-bit raw of 2^53 + 1 is a double's 2^53). Empty otherwise.
std::string dbc_physical_exact(const DbcSignal& s, uint64_t raw);
// The raw value that stands for `physical` (rounded to the nearest step; IEEE bits for a
// float signal): the encoder of tests and emulators.
uint64_t dbc_raw_of(const DbcSignal& s, double physical);
// Whether every bit of the signal lies inside `bytes` payload bytes.
bool dbc_signal_fits(const DbcSignal& s, int bytes);
// The payload bits (byte * 8 + bit in byte, up to 64 bytes) that hold the raw bits of `s` set in
// `raw_bits` (all of them by default; bit 0 = the raw value's least significant bit).
std::bitset<512> dbc_signal_bits(const DbcSignal& s, uint64_t raw_bits = ~uint64_t{0});
// Whether two signals of one message can be in one frame: not in two different multiplexed
// branches (m1 and m2 never appear in the same frame).
bool dbc_same_frame(const DbcSignal& a, const DbcSignal& b);

// Reading candump logs (LoggedFrame, parse_candump_line) is firmware_link/candump_log.hpp.

}  // namespace rig::link
