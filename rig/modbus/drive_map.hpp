// A CiA 402 drive map: where a particular servo drive puts the CiA 402 objects
// on its Modbus registers (address, function, width, signedness, word order)
// and how its units relate to the table's degrees (encoder counts, gear ratio,
// direction, velocity/acceleration units), its homing method and offset and
// the travel limits. Read from a TOML file (drives/*.toml, written from the
// drive's manual: docs/cia402-drive-maps.md); shared by the rig's client and
// the emulated drive so both ends agree.
#pragma once
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <toml++/toml.h>

namespace rig::modbus {

// The objects the rig uses. The first kRequiredCount are required in every map.
enum class Obj : int {
  kControlword,
  kStatusword,
  kErrorCode,
  kModesOfOperation,
  kModesDisplay,
  kPositionActual,
  kVelocityActual,
  kTargetPosition,
  // optional
  kProfileVelocity,
  kProfileAcceleration,
  kProfileDeceleration,
  kQuickStopDeceleration,
  kHomingMethod,
  kHomeOffset,
  kFollowingErrorActual,
  kDeviceType,  // 0x1000: when mapped, the client checks it reads profile 402 before any write
  kCount
};
inline constexpr int kObjCount = static_cast<int>(Obj::kCount);
inline constexpr int kRequiredCount = static_cast<int>(Obj::kProfileVelocity);

struct ObjectInfo {
  const char* key;   // the map file's key, "target_position"
  uint16_t index;    // CiA 402 object index, 0x607A
  bool writable;     // the rig writes it (must be a holding register)
};
const ObjectInfo& object_info(Obj o);

struct ObjectSpec {
  bool present = false;
  uint16_t address = 0;     // 0-based PDU address, address_base included
  bool input = false;       // function 04 (input register) instead of 03 (holding)
  int width = 16;           // 16 or 32 bits
  bool is_signed = false;
  bool low_word_first = false;
  int words() const { return width / 16; }
};

enum class VelocityUnit { kCountsPerS, kRpm };        // rpm = motor revolutions per minute
enum class AccelUnit { kCountsPerS2, kRpmPerS };

struct DriveMap {
  std::string path;   // the file it came from
  std::string name;   // [drive] name
  std::array<ObjectSpec, kObjCount> objects{};
  double counts_per_rev = 0;  // encoder counts per motor revolution
  double gear_ratio = 1;      // motor revolutions per table (output) revolution
  int direction = 1;          // -1: positive counts turn the table negatively
  VelocityUnit velocity_unit = VelocityUnit::kCountsPerS;
  AccelUnit accel_unit = AccelUnit::kCountsPerS2;
  // One unit of the drive's velocity (acceleration) objects in velocity_unit (acceleration_unit):
  // 0.1 for a drive that counts speed in 0.1 rpm. 1 unless [scaling] says otherwise.
  double velocity_resolution = 1, accel_resolution = 1;
  int homing_method = 0;      // 0 = leave the drive's own setting
  double home_offset_deg = 0;
  double limit_neg_deg = -190, limit_pos_deg = 370;
  std::optional<int> homed_bit;  // manufacturer-specific statusword bit "reference known"

  const ObjectSpec& spec(Obj o) const { return objects[static_cast<int>(o)]; }
  bool has(Obj o) const { return spec(o).present; }

  // Position: table degrees <-> drive position units (encoder counts).
  double counts_per_deg() const { return counts_per_rev * gear_ratio / 360.0; }
  int64_t deg_to_counts(double deg) const;
  double counts_to_deg(int64_t counts) const;
  // Velocity / acceleration magnitudes in the drive's units (never negative for profile values).
  double dps_to_velocity_units(double dps) const;
  double velocity_units_to_dps(double v) const;   // signed, direction applied
  double dps2_to_accel_units(double dps2) const;
  double accel_units_to_dps2(double a) const;
  // One drive unit in words, after a number of them: "rpm", "counts/s", "× 0.1 rpm" (velocity);
  // "rpm/s", "counts/s²", "× 0.01 rpm/s" (acceleration).
  std::string velocity_unit_text() const;
  std::string accel_unit_text() const;

  // Whether `value` fits the object's register (its width and signedness), and that range as
  // text ("a 16-bit unsigned register: 0..65535") for messages.
  bool fits(Obj o, int64_t value) const;
  std::string range_text(Obj o) const;
  // Register codec of an object: words in the order the drive puts them. A value that does not
  // fit is a ConfigError naming the object (never its low bits: a velocity of 87381 counts/s in
  // 16 bits was 21845, and the table crept at a tenth of its speed, a review).
  std::vector<uint16_t> encode(Obj o, int64_t value) const;
  int64_t decode(Obj o, const uint16_t* words) const;
  // "target_position (0x607A) at holding register 16" for messages.
  std::string describe(Obj o) const;
};

// Reads and checks a map file. Unknown keys, a missing required object,
// overlapping registers, bad widths/functions/units: ConfigError naming file:line:col.
DriveMap load_drive_map(const std::string& path);
DriveMap parse_drive_map(const toml::table& root, const std::string& path);

}  // namespace rig::modbus
