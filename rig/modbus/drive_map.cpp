#include "rig/modbus/drive_map.hpp"

#include <algorithm>
#include <tuple>
#include <cmath>
#include <cstdio>

#include "rig/core/errors.hpp"
#include "rig/core/escape.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/modbus/cia402.hpp"

namespace rig::modbus {

namespace o = cia402::obj;

const ObjectInfo& object_info(Obj ob) {
  static const std::array<ObjectInfo, kObjCount> kInfo = {{
      {"controlword", o::kControlword, true},
      {"statusword", o::kStatusword, false},
      {"error_code", o::kErrorCode, false},
      {"modes_of_operation", o::kModesOfOperation, true},
      {"modes_of_operation_display", o::kModesDisplay, false},
      {"position_actual", o::kPositionActual, false},
      {"velocity_actual", o::kVelocityActual, false},
      {"target_position", o::kTargetPosition, true},
      {"profile_velocity", o::kProfileVelocity, true},
      {"profile_acceleration", o::kProfileAcceleration, true},
      {"profile_deceleration", o::kProfileDeceleration, true},
      {"quick_stop_deceleration", o::kQuickStopDeceleration, true},
      {"homing_method", o::kHomingMethod, true},
      {"home_offset", o::kHomeOffset, true},
      {"following_error_actual", o::kFollowingErrorActual, false},
      {"device_type", o::kDeviceType, false},
  }};
  return kInfo[static_cast<int>(ob)];
}

namespace {

std::string hex4(unsigned v) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%04X", v);
  return b;
}

[[noreturn]] void fail(const toml::node& n, const std::string& msg) { throw ConfigError(cfg::where(n) + ": " + msg); }
std::string shown(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", x);
  return b;
}

bool parse_word_order(const toml::table& t, std::string_view key, bool def) {
  const toml::node* n = t.get(key);
  if (!n) return def;
  const std::string s = cfg::get_string(t, key);
  if (s == "high_first") return false;
  if (s == "low_first") return true;
  fail(*n, "'" + std::string(key) + "' = \"" + s + "\": expected \"high_first\" or \"low_first\"");
}

}  // namespace

int64_t DriveMap::deg_to_counts(double deg) const { return std::llround(deg * counts_per_deg() * direction); }
double DriveMap::counts_to_deg(int64_t counts) const {
  return static_cast<double>(counts) * direction / counts_per_deg() + 0.0;  // + 0.0: no "-0.0000°" for 0 counts
}

// In the drive's units: the value in velocity_unit (acceleration_unit) over the size of one unit.
double DriveMap::dps_to_velocity_units(double dps) const {
  dps = std::fabs(dps);
  const double v = velocity_unit == VelocityUnit::kCountsPerS ? dps * counts_per_deg() : dps / 360.0 * gear_ratio * 60.0;
  return v / velocity_resolution;
}
double DriveMap::velocity_units_to_dps(double units) const {
  const double v = units * velocity_resolution;
  const double dps = velocity_unit == VelocityUnit::kCountsPerS ? v / counts_per_deg() : v / 60.0 / gear_ratio * 360.0;
  return dps * direction;
}
double DriveMap::dps2_to_accel_units(double a) const {
  a = std::fabs(a);
  const double v = accel_unit == AccelUnit::kCountsPerS2 ? a * counts_per_deg() : a / 360.0 * gear_ratio * 60.0;
  return v / accel_resolution;
}
double DriveMap::accel_units_to_dps2(double units) const {
  const double a = units * accel_resolution;
  return accel_unit == AccelUnit::kCountsPerS2 ? a / counts_per_deg() : a / 60.0 / gear_ratio * 360.0;
}

namespace {
std::string unit_text(double resolution, const char* unit) {
  if (resolution == 1) return unit;
  char b[32];
  std::snprintf(b, sizeof b, "× %.15g ", resolution);
  return b + std::string(unit);
}
}  // namespace

std::string DriveMap::velocity_unit_text() const {
  return unit_text(velocity_resolution, velocity_unit == VelocityUnit::kRpm ? "rpm" : "counts/s");
}
std::string DriveMap::accel_unit_text() const {
  return unit_text(accel_resolution, accel_unit == AccelUnit::kRpmPerS ? "rpm/s" : "counts/s²");
}

namespace {
std::pair<int64_t, int64_t> register_range(const ObjectSpec& s) {
  const int64_t span = int64_t{1} << s.width;
  return s.is_signed ? std::pair{-span / 2, span / 2 - 1} : std::pair{int64_t{0}, span - 1};
}
}  // namespace

bool DriveMap::fits(Obj ob, int64_t v) const {
  const auto [lo, hi] = register_range(spec(ob));
  return v >= lo && v <= hi;
}

namespace {
// A register address as maps write them: hex (0x200A) beside the decimal (a review: a map in hex
// with an address_base read "registers 8202..8203").
std::string reg_text(uint32_t a) {
  char b[32];
  std::snprintf(b, sizeof b, "0x%04X (%u)", a, a);
  return b;
}
}  // namespace

std::string DriveMap::range_text(Obj ob) const {
  const ObjectSpec& s = spec(ob);
  const auto [lo, hi] = register_range(s);
  return "a " + std::to_string(s.width) + "-bit " + (s.is_signed ? "signed" : "unsigned") + " register: " +
         std::to_string(lo) + ".." + std::to_string(hi);
}

std::vector<uint16_t> DriveMap::encode(Obj ob, int64_t v) const {
  const ObjectSpec& s = spec(ob);
  if (!fits(ob, v))
    throw ConfigError("drive map " + path + ": " + std::to_string(v) + " does not fit " + describe(ob) + ", " +
                      range_text(ob));
  const auto u = static_cast<uint32_t>(v);
  if (s.width == 16) return {static_cast<uint16_t>(u & 0xFFFFu)};
  const auto hi = static_cast<uint16_t>(u >> 16), lo = static_cast<uint16_t>(u & 0xFFFFu);
  return s.low_word_first ? std::vector<uint16_t>{lo, hi} : std::vector<uint16_t>{hi, lo};
}

int64_t DriveMap::decode(Obj ob, const uint16_t* w) const {
  const ObjectSpec& s = spec(ob);
  if (s.width == 16) return s.is_signed ? static_cast<int64_t>(static_cast<int16_t>(w[0])) : w[0];
  const uint32_t u = s.low_word_first ? (static_cast<uint32_t>(w[1]) << 16) | w[0]
                                      : (static_cast<uint32_t>(w[0]) << 16) | w[1];
  return s.is_signed ? static_cast<int64_t>(static_cast<int32_t>(u)) : static_cast<int64_t>(u);
}

std::string DriveMap::describe(Obj ob) const {
  const ObjectInfo& i = object_info(ob);
  const ObjectSpec& s = spec(ob);
  return std::string(i.key) + " (" + hex4(i.index) + ") at " + (s.input ? "input" : "holding") + " register " +
         std::to_string(s.address);
}

DriveMap load_drive_map(const std::string& path) { return parse_drive_map(cfg::parse_file(path), path); }

DriveMap parse_drive_map(const toml::table& root, const std::string& path) {
  DriveMap m;
  m.path = path;
  cfg::check_keys(root, {"drive", "scaling", "homing", "limits", "objects"}, "drive map");
  const toml::table& drive = *cfg::get_table(root, "drive", true);
  cfg::check_keys(drive, {"name", "address_base", "word_order"}, "drive");
  m.name = cfg::get_string(drive, "name");
  // The name is how every message and `rig table status` tells which drive they mean: "" read
  // 'drive ""' (a review), a control character reached the terminal as it was.
  if (m.name.empty() || has_unshowable(m.name))
    throw ConfigError(cfg::where(*drive.get("name")) + ": 'name' = \"" + shown_text(m.name) + "\": " +
                      (m.name.empty() ? "the drive's name is required, not empty"
                                      : "a control character (shown here as \\xNN) cannot be in the drive's name"));
  const auto base = cfg::get_int(drive, "address_base", 0, 0, 65535);
  const bool low_first = parse_word_order(drive, "word_order", false);

  const toml::table& sc = *cfg::get_table(root, "scaling", true);
  cfg::check_keys(sc, {"counts_per_rev", "gear_ratio", "direction", "velocity_unit", "acceleration_unit",
                       "velocity_resolution", "acceleration_resolution"},
                  "scaling");
  m.counts_per_rev = cfg::get_number(sc, "counts_per_rev", {}, 1.0, 1e12);
  // An encoder counts whole counts: 1048576.5 is a typo, and would shift every angle.
  if (m.counts_per_rev != std::floor(m.counts_per_rev))
    cfg::reject(*sc.get("counts_per_rev"), "counts_per_rev", "encoder counts per revolution are a whole number");
  m.gear_ratio = cfg::get_number(sc, "gear_ratio", 1.0, 1e-6, 1e6);
  m.direction = static_cast<int>(cfg::get_int(sc, "direction", 1, -1, 1));
  if (m.direction == 0) fail(*sc.get("direction"), "'direction' must be 1 or -1");
  const std::string vu = cfg::get_string(sc, "velocity_unit", std::string("counts_per_s"));
  if (vu == "counts_per_s") {
    m.velocity_unit = VelocityUnit::kCountsPerS;
  } else if (vu == "rpm") {
    m.velocity_unit = VelocityUnit::kRpm;
  } else {
    fail(*sc.get("velocity_unit"), "'velocity_unit' = \"" + vu + "\": expected \"counts_per_s\" or \"rpm\"");
  }
  const std::string au = cfg::get_string(sc, "acceleration_unit", std::string("counts_per_s2"));
  if (au == "counts_per_s2") {
    m.accel_unit = AccelUnit::kCountsPerS2;
  } else if (au == "rpm_per_s") {
    m.accel_unit = AccelUnit::kRpmPerS;
  } else {
    fail(*sc.get("acceleration_unit"), "'acceleration_unit' = \"" + au + "\": expected \"counts_per_s2\" or \"rpm_per_s\"");
  }
  // A drive that counts speed in 0.1 rpm (or acceleration in 0.01 rpm/s) says so here; without
  // it such a drive turned at ten times the speed the rig meant (docs/cia402-drive-maps.md).
  m.velocity_resolution = cfg::get_number(sc, "velocity_resolution", 1.0, 1e-9, 1e9);
  m.accel_resolution = cfg::get_number(sc, "acceleration_resolution", 1.0, 1e-9, 1e9);

  if (const toml::table* h = cfg::get_table(root, "homing")) {
    cfg::check_keys(*h, {"method", "offset_deg", "homed_bit"}, "homing");
    // Methods 1..37 of IEC 61800-7-201 (negative values are manufacturer specific).
    m.homing_method = static_cast<int>(cfg::get_int(*h, "method", 0, -128, 37));
    m.home_offset_deg = cfg::get_number(*h, "offset_deg", 0.0, -360.0, 360.0);
    if (h->contains("homed_bit")) {
      m.homed_bit = static_cast<int>(cfg::get_int(*h, "homed_bit", {}, 14, 15));
    }
  }
  const toml::table& lim = *cfg::get_table(root, "limits", true);
  cfg::check_keys(lim, {"neg_deg", "pos_deg"}, "limits");
  // The travel holds 0° (the frame's zero; docs/cia402-drive-maps.md, 9): a positive neg_deg
  // was refused "out of range [-200000, 0]" with no word of why (a review).
  for (const auto& [key, sign] : {std::pair{"neg_deg", -1.0}, std::pair{"pos_deg", 1.0}})
    if (const toml::node* n = lim.get(key); n && n->value<double>() && *n->value<double>() * sign < 0)
      cfg::reject(*n, key,
                  std::string("the travel must hold 0° (neg_deg <= 0 <= pos_deg): move the drive's zero into its travel "
                              "with [homing] offset_deg (0x607C) and give the procedure's angles in that frame"));
  m.limit_neg_deg = cfg::get_number(lim, "neg_deg", {}, -200000.0, 0.0);
  m.limit_pos_deg = cfg::get_number(lim, "pos_deg", {}, 0.0, 200000.0);
  // Both 0: a table that cannot move, which every angle of the procedure then "left" (a review:
  // the refusal named the profile's u20_deg, not the map).
  if (m.limit_neg_deg == m.limit_pos_deg)
    cfg::reject(*lim.get("pos_deg"), "pos_deg",
                "[limits] neg_deg = pos_deg = 0: no travel at all; give the drive's software limits (its manual, "
                "objects 0x607D)");

  const toml::table& objs = *cfg::get_table(root, "objects", true);
  std::vector<std::string_view> names;
  for (int i = 0; i < kObjCount; ++i) names.push_back(object_info(static_cast<Obj>(i)).key);
  for (const auto& [k, node] : objs) {
    if (std::find(names.begin(), names.end(), k.str()) == names.end())
      fail(node, "unknown object '" + std::string(k.str()) + "' in [objects] (see docs/cia402-drive-maps.md)");
  }
  struct Span {
    int obj;
    bool input;
    uint32_t lo, hi;
    const toml::node* node;
  };
  std::vector<Span> spans;
  for (int i = 0; i < kObjCount; ++i) {
    const Obj ob = static_cast<Obj>(i);
    const ObjectInfo& info = object_info(ob);
    const toml::node* n = objs.get(info.key);
    if (!n) {
      if (i < kRequiredCount)
        fail(objs, "[objects] is missing the required object '" + std::string(info.key) + "' (" + hex4(info.index) + ")");
      continue;
    }
    const toml::table* t = n->as_table();
    if (!t) fail(*n, "'" + std::string(info.key) + "' must be a table { index = ..., address = ..., ... }");
    // "[objects.controlword]": it read "[controlword]", a section the file does not have (a review).
    cfg::check_keys(*t, {"index", "address", "function", "width", "signed", "word_order"},
                    "objects." + std::string(info.key));
    const auto index = cfg::get_int(*t, "index", {}, 0, 0xFFFF);
    if (index != info.index)
      fail(*t->get("index"), "'" + std::string(info.key) + "' is object " + hex4(info.index) + ", not " +
                                  hex4(static_cast<unsigned>(index)));
    ObjectSpec s;
    s.present = true;
    const auto offset = cfg::get_int(*t, "address", {}, 0, 65535);
    const auto addr = base + offset;
    const std::string fn = cfg::get_string(*t, "function", std::string("holding"));
    if (fn != "holding" && fn != "input")
      fail(*t->get("function"), "'function' = \"" + fn + "\": expected \"holding\" or \"input\"");
    s.input = fn == "input";
    if (s.input && info.writable)
      fail(*t->get("function"), "'" + std::string(info.key) + "' is written by the rig: it must be a holding register");
    s.width = static_cast<int>(cfg::get_int(*t, "width", 16, 16, 32));
    if (s.width != 16 && s.width != 32) fail(*t->get("width"), "'width' must be 16 or 32");
    s.is_signed = cfg::get_bool(*t, "signed", false);
    // UNSIGNED16 in the standard (section 1.4 of docs/cia402-drive-maps.md): a signed statusword
    // or controlword would misread bit 15 and refuse words above 0x7FFF.
    if (s.is_signed && (ob == Obj::kControlword || ob == Obj::kStatusword || ob == Obj::kErrorCode))
      cfg::reject(*t->get("signed"), "signed", "'" + std::string(info.key) + "' is unsigned (UNSIGNED16 in CiA 402)");
    s.low_word_first = parse_word_order(*t, "word_order", low_first);
    // A 16-bit object has one word, so no order: a word_order there says the map's author took
    // the object for 32 bits, and the width is the likelier mistake (a review: accepted silently).
    if (s.width == 16 && t->get("word_order"))
      cfg::reject(*t->get("word_order"), "word_order",
                  "'" + std::string(info.key) + "' is 16 bits wide (one register), so it has no word order; if "
                  "the drive's manual gives it two registers, set width = 32");
    if (addr + s.words() > 65536)
      fail(*t->get("address"), "'" + std::string(info.key) + "' at register " + std::to_string(addr) +
                                   (base ? " ([drive] address_base " + std::to_string(base) + " + address " +
                                               std::to_string(offset) + ")"
                                         : std::string()) +
                                   " with its " + std::to_string(s.words()) + " word(s) goes beyond register 65535");
    s.address = static_cast<uint16_t>(addr);
    m.objects[i] = s;
    const auto lo = static_cast<uint32_t>(addr);
    for (const Span& o2 : spans) {
      if (o2.input == s.input && lo < o2.hi && o2.lo < lo + s.words())
        fail(*t, "'" + std::string(info.key) + "' (registers " + reg_text(lo) + ".." + reg_text(lo + s.words() - 1) +
                     ") overlaps '" + object_info(static_cast<Obj>(o2.obj)).key +
                     "' at " + cfg::where(*o2.node));
    }
    spans.push_back({i, s.input, lo, lo + s.words(), t});
  }
  if (m.homing_method != 0 && !m.has(Obj::kHomingMethod))
    fail(*cfg::get_table(root, "homing"), "[homing] method is set but [objects] has no homing_method (0x6098)");
  if (m.home_offset_deg != 0 && !m.has(Obj::kHomeOffset))
    fail(*cfg::get_table(root, "homing"), "[homing] offset_deg is set but [objects] has no home_offset (0x607C)");
  // Every angle the rig writes or reads lies within the travel limits (and the home offset):
  // their counts must fit the position registers, or a target would wrap to another angle.
  for (const auto& [key, deg, node] : {std::tuple{"neg_deg", m.limit_neg_deg, lim.get("neg_deg")},
                                      {"pos_deg", m.limit_pos_deg, lim.get("pos_deg")}})
    for (const Obj ob : {Obj::kTargetPosition, Obj::kPositionActual})
      if (m.has(ob) && !m.fits(ob, m.deg_to_counts(deg)))
        fail(*node, std::string("[limits] ") + key + " = " + shown(deg) + " is " +
                        std::to_string(m.deg_to_counts(deg)) + " counts, which does not fit " + m.describe(ob) + ", " +
                        m.range_text(ob) + " (counts_per_rev x gear_ratio too large for the register, or 'signed' "
                        "left out)");
  // After homing the table reads the offset: outside the travel, every move from home would be
  // refused and the table would stand where the map says it cannot be (a review: 250° with [-10, 200]).
  if (m.home_offset_deg < m.limit_neg_deg || m.home_offset_deg > m.limit_pos_deg)
    cfg::reject(*cfg::get_table(root, "homing")->get("offset_deg"), "offset_deg",
                "outside the travel [limits] " + shown(m.limit_neg_deg) + ".." + shown(m.limit_pos_deg) +
                    ": the table would read it after homing");
  if (m.homing_method != 0 && !m.fits(Obj::kHomingMethod, m.homing_method))  // e.g. -1 without signed = true
    fail(*cfg::get_table(root, "homing")->get("method"), "[homing] method = " + std::to_string(m.homing_method) +
                                                             " does not fit " + m.describe(Obj::kHomingMethod) + ", " +
                                                             m.range_text(Obj::kHomingMethod));
  if (m.home_offset_deg != 0 && !m.fits(Obj::kHomeOffset, m.deg_to_counts(m.home_offset_deg)))
    fail(*cfg::get_table(root, "homing")->get("offset_deg"),
         "[homing] offset_deg does not fit " + m.describe(Obj::kHomeOffset) + ", " + m.range_text(Obj::kHomeOffset));
  return m;
}

}  // namespace rig::modbus
