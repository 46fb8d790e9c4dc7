#include "firmware_link/dbc_stream.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>

#include "rig/core/errors.hpp"
#include "rig/core/escape.hpp"
#include "rig/core/toml_util.hpp"

namespace rig::link {

extern const char* const kRigDutDbcText;  // docs/rig-dut.dbc, built in (rig_dut_dbc.cpp, generated)

namespace {

constexpr uint8_t kFlagBits[3] = {stream_status::kFilterOn, stream_status::kSaturated, stream_status::kLoopFault};

// The factor from a signal's unit to g (the Sample's unit).
double unit_to_g(const std::string& unit, const std::string& what, const std::string& where) {
  // A sample without a unit is not taken as g: a DBC often leaves the unit out, and a signal in
  // counts or mg read as g is wrong by orders of magnitude with nothing to show it (a review).
  if (unit.empty())
    throw ConfigError(where + ": " + what + " has no unit in the DBC; give it the acceleration unit its factor "
                      "yields (g, mg, ug or m/s^2)");
  if (unit == "g") return 1.0;
  if (unit == "mg") return 1e-3;
  // The micro sign (a Windows-1252 file's byte 0xB5 is read as it, Dbc::parse) or the Greek small
  // mu a keyboard gives for it.
  if (unit == "ug" || unit == "\xC2\xB5g" || unit == "\xCE\xBCg") return 1e-6;
  if (unit == "m/s^2" || unit == "m/s2" || unit == "m/s\xC2\xB2") return 1.0 / 9.80665;
  throw ConfigError(where + ": " + what + " has unit '" + shown_text(unit) + "', not an acceleration (g, mg, ug, m/s^2)");
}

}  // namespace

namespace {
// The counter and each x and y read bits of their own, and no status bit or flag the stream reads
// lies in them: a DBC may alias bits on purpose (a status word and its one-bit flags, a status word
// that also holds the counter), but a sample sharing a bit with the counter or with a flag it reads
// (or one signal named in two roles) would decode plausible nonsense. Of a status signal only the
// bits the *_bit keys name are read, so only those count.
template <class Roles, class Fail>
void check_no_shared_bits(const Roles& r, uint64_t status_bits, const std::string& dbc_source, const Fail& fail) {
  struct Role {
    std::string name;
    const DbcSignal* s;
    std::bitset<512> bits;
  };
  std::vector<Role> data{{"counter", r.counter, dbc_signal_bits(*r.counter)}}, control;
  const char* const flag_names[3] = {"filter_on", "saturated", "loop_fault"};
  for (const auto& sl : r.samples) {
    if (sl.x) data.push_back({"x", sl.x, dbc_signal_bits(*sl.x)});
    if (sl.y) data.push_back({"y", sl.y, dbc_signal_bits(*sl.y)});
    if (sl.status) control.push_back({"status", sl.status, dbc_signal_bits(*sl.status, status_bits)});
    for (int k = 0; k < 3; ++k)
      if (sl.flag[k]) control.push_back({flag_names[k], sl.flag[k], dbc_signal_bits(*sl.flag[k])});
  }
  auto name = [&](const Role& o) {
    return o.name + " " + r.msg->name + "." + o.s->name + " (" + std::to_string(o.s->start) + "|" +
           std::to_string(o.s->length) + ", " + dbc_source + ":" + std::to_string(o.s->line) + ")";
  };
  auto shared = [](const Role& a, const Role& b) { return dbc_same_frame(*a.s, *b.s) && (a.bits & b.bits).any(); };
  for (std::size_t i = 0; i < data.size(); ++i) {
    for (std::size_t j = i + 1; j < data.size(); ++j)
      if (shared(data[i], data[j]))
        fail(name(data[i]) + " and " + name(data[j]) + " share bits: the counter, x and y each need their own");
    for (const Role& c : control)
      if (shared(data[i], c))
        fail(name(data[i]) + " and " + name(c) + " share bits: no status bit or flag the stream reads may lie in the "
                                                 "counter, x or y");
  }
}
}  // namespace

DbcStreamDecoder::DbcStreamDecoder(std::shared_ptr<const Dbc> dbc, DbcStreamSpec spec, const std::string& where)
    : dbc_(std::move(dbc)), spec_(std::move(spec)) {
  // Every message starts with the key it is about ("y = ...", "filter_on_bit = ..."): named at
  // that key's line where the spec knows it.
  auto fail = [&](const std::string& m) {
    const auto at = spec_.key_where.find(m.substr(0, m.find(' ')));
    throw ConfigError((at != spec_.key_where.end() ? at->second : where) + ": " + m);
  };
  struct Ref {
    const DbcMessage* msg = nullptr;
    std::string sig;
  };
  auto ref = [&](const std::string& role, const std::string& name) {
    const auto dot = name.find('.');
    if (dot == std::string::npos || dot == 0 || dot + 1 == name.size())
      fail(role + " = \"" + name + "\" is not MESSAGE.SIGNAL");
    Ref r{dbc_->find(name.substr(0, dot)), name.substr(dot + 1)};
    if (!r.msg) fail(role + " = \"" + name + "\": the DBC has no message " + name.substr(0, dot));
    return r;
  };
  const int n = spec_.samples_per_frame;
  if (n < 1 || n > 64) fail("samples_per_frame = " + std::to_string(n) + " is not 1..64");
  if (!(spec_.rate_hz > 0 && spec_.rate_hz <= 1e6)) fail("rate_hz = " + std::to_string(spec_.rate_hz) + " is not in (0, 1e6]");
  if (spec_.counter.empty() || spec_.x.empty()) fail("the stream needs `counter` and `x`");

  const Ref counter = ref("counter", spec_.counter);
  const DbcSignal* cs = counter.msg->signal(counter.sig);
  if (!cs) fail("counter = \"" + spec_.counter + "\": no signal " + counter.sig + " in " + counter.msg->name);
  if (cs->value_type != 0 || cs->length < 2 || cs->length > 32)
    fail("counter " + spec_.counter + " must be an integer signal of 2..32 bits (has " + std::to_string(cs->length) +
         (cs->value_type ? ", float" : "") + ")");
  // The counter's raw value is the sample count: a factor or offset would make the DBC's physical
  // value another number than the one the stream reads (it was accepted and its raw value used).
  auto unscaled = [&](const std::string& name, const DbcSignal& c) {
    if (c.factor != 1 || c.offset != 0) {
      char b[64];
      std::snprintf(b, sizeof b, "(%g,%g)", c.factor, c.offset);
      fail("counter " + name + " is scaled in the DBC " + b + ", " + dbc_->source() + ":" + std::to_string(c.line) +
           ": a sample counter is a whole number, factor 1 and offset 0");
    }
  };
  unscaled(spec_.counter, *cs);
  counter_bits_ = cs->length;

  // The roles' references; the messages they name carry parts of samples.
  const Ref x = ref("x", spec_.x);
  std::optional<Ref> y, status, flag[3];
  if (!spec_.y.empty()) y = ref("y", spec_.y);
  if (!spec_.status.empty()) status = ref("status", spec_.status);
  const std::string* flag_names[3] = {&spec_.filter_on, &spec_.saturated, &spec_.loop_fault};
  const int* flag_bits[3] = {&spec_.filter_on_bit, &spec_.saturated_bit, &spec_.loop_fault_bit};
  const char* flag_keys[3] = {"filter_on", "saturated", "loop_fault"};
  for (int k = 0; k < 3; ++k) {
    if (!flag_names[k]->empty()) flag[k] = ref(flag_keys[k], *flag_names[k]);
    if (*flag_bits[k] < -1 || *flag_bits[k] > 63)
      fail(std::string(flag_keys[k]) + "_bit = " + std::to_string(*flag_bits[k]) + " is not a bit number");
    if (*flag_bits[k] >= 0 && !status) fail(std::string(flag_keys[k]) + "_bit needs `status`");
    if (*flag_bits[k] >= 0 && flag[k]) fail(std::string(flag_keys[k]) + " is given as a signal and as a status bit");
  }
  for (int k = 0; k < 3; ++k)  // two flags on one bit would always read alike
    for (int j = 0; j < k; ++j)
      if (*flag_bits[k] >= 0 && *flag_bits[k] == *flag_bits[j])
        fail(std::string(flag_keys[k]) + "_bit = " + std::to_string(*flag_bits[k]) + " is also " + flag_keys[j] +
             "_bit: each flag needs its own bit");
  if (status && spec_.filter_on_bit < 0 && spec_.saturated_bit < 0 && spec_.loop_fault_bit < 0)
    fail("status = \"" + spec_.status + "\" names no bit (filter_on_bit, saturated_bit, loop_fault_bit)");

  uint64_t status_bits = 0;  // the raw bits of `status` the stream reads
  for (int k = 0; k < 3; ++k)
    if (*flag_bits[k] >= 0) status_bits |= uint64_t{1} << *flag_bits[k];

  std::set<const DbcMessage*> msgs{x.msg};
  if (y) msgs.insert(y->msg);
  // The signal of sample i: "NAMEi" with several samples per frame, else "NAME"; a shared
  // (unindexed) signal is allowed where `shared_ok`.
  auto lookup = [&](const DbcMessage* m, const std::string& base, int i, bool shared_ok) -> const DbcSignal* {
    if (n == 1) return m->signal(base);
    if (const DbcSignal* s = m->signal(base + std::to_string(i))) return s;
    return shared_ok ? m->signal(base) : nullptr;
  };
  for (const DbcMessage* m : msgs) {
    Roles r;
    r.msg = m;
    r.counter = m->signal(counter.sig);
    if (!r.counter)  // said at the key that put the message in the stream (a review: at the table's line)
      fail((m == x.msg ? "x = \"" + spec_.x : "y = \"" + spec_.y) + "\": message " + m->name +
           " carries part of a sample but no counter signal '" + counter.sig + "'");
    if (r.counter->length != counter_bits_ || r.counter->value_type != 0)
      fail("counter " + m->name + "." + counter.sig + " has " + std::to_string(r.counter->length) + " bits, " +
           spec_.counter + " has " + std::to_string(counter_bits_));
    unscaled(m->name + "." + counter.sig, *r.counter);
    r.samples.resize(static_cast<std::size_t>(n));
    // A counter on one multiplexer page only: a sample on any other page (or on every page) would
    // arrive with no counter in its frame, every frame (a review: such a layout was accepted and
    // `rig capture import` then kept 0 samples).
    const auto same_page = [&](const char* role, const DbcSignal* s) {
      if (s && r.counter->mux_value && s->mux_value != r.counter->mux_value)
        fail(std::string(role) + " " + m->name + "." + s->name + " is " +
             (s->mux_value ? "on multiplexer page " + std::to_string(*s->mux_value) : std::string("on every page")) +
             ", but counter " + m->name + "." + r.counter->name + " only on page " +
             std::to_string(*r.counter->mux_value) + ": those frames would carry no counter");
    };
    for (int i = 0; i < n; ++i) {
      Slot& sl = r.samples[static_cast<std::size_t>(i)];
      if (m == x.msg) {
        sl.x = lookup(m, x.sig, i, false);
        if (!sl.x) fail("x = \"" + spec_.x + "\": no signal " + x.sig + (n > 1 ? std::to_string(i) : "") + " in " + m->name);
        same_page("x", sl.x);
      }
      if (y && m == y->msg) {
        sl.y = lookup(m, y->sig, i, false);
        if (!sl.y) fail("y = \"" + spec_.y + "\": no signal " + y->sig + (n > 1 ? std::to_string(i) : "") + " in " + m->name);
        same_page("y", sl.y);
      }
      // Status and flags: required in the message named, taken from the others where present.
      if (status) {
        sl.status = lookup(m, status->sig, i, true);
        if (!sl.status && m == status->msg) fail("status = \"" + spec_.status + "\": no such signal in " + m->name);
        if (sl.status && sl.status->value_type != 0) fail("status " + m->name + "." + sl.status->name + " is a float");
        // A flag bit the status signal does not have could never be set (a review: bit 12 of an
        // 8-bit status passed).
        for (int k = 0; k < 3 && sl.status; ++k)
          if (*flag_bits[k] >= sl.status->length)
            fail(std::string(flag_keys[k]) + "_bit = " + std::to_string(*flag_bits[k]) + " is beyond status " +
                 m->name + "." + sl.status->name + ", which has " + std::to_string(sl.status->length) + " bits (0.." +
                 std::to_string(sl.status->length - 1) + ")");
      }
      for (int k = 0; k < 3; ++k)
        if (flag[k]) {
          sl.flag[k] = lookup(m, flag[k]->sig, i, true);
          if (!sl.flag[k] && m == flag[k]->msg)
            fail(std::string(flag_keys[k]) + " = \"" + *flag_names[k] + "\": no such signal in " + m->name);
        }
    }
    // The message holding one more sample than samples_per_frame says: every frame's last sample
    // would be left out, imported as one lost sample per frame (a review: x0..x3 with
    // samples_per_frame = 3 passed).
    // Any numbered one past it too (x0..x2 with x7: a re-test).
    if (n > 1)
      for (const auto& [role, base, is_here] : {std::tuple{"x", x.sig, m == x.msg}, std::tuple{"y", y ? y->sig : std::string(), y && m == y->msg}})
        for (const DbcSignal& sig : m->signals) {
          if (!is_here || sig.name.size() <= base.size() || sig.name.compare(0, base.size(), base) != 0) continue;
          const std::string num = sig.name.substr(base.size());
          if (num.size() > 3 || !std::all_of(num.begin(), num.end(), [](char c) { return c >= '0' && c <= '9'; }))
            continue;
          if (const int k = std::stoi(num); k >= n)
            fail("samples_per_frame = " + std::to_string(n) + ": message " + m->name + " also has " + sig.name + " (" +
                 role + " of a sample " + std::to_string(k + 1) +
                 "): a frame's samples are numbered 0..samples_per_frame-1, and this one would never be read");
        }
    // A status or flag on a multiplexer page with no x or y of its sample: the decoder gives a
    // frame's flags to that frame's x and y, so they would reach no sample (a code review: the
    // emulator sent such a page, and 200 saturated samples decoded as 0).
    for (const Slot& sl : r.samples) {
      const auto on_a_sample_page = [&](const DbcSignal* s) {
        const auto with = [&](const DbcSignal* v) { return v && (!v->mux_value || v->mux_value == s->mux_value); };
        return !s || !s->mux_value || with(sl.x) || with(sl.y);
      };
      const DbcSignal* lone = !on_a_sample_page(sl.status) ? sl.status : nullptr;
      for (int k = 0; k < 3 && !lone; ++k)
        if (!on_a_sample_page(sl.flag[k])) lone = sl.flag[k];
      if (lone)
        fail(m->name + "." + lone->name + " is on multiplexer page " + std::to_string(*lone->mux_value) + ", where " +
             m->name + " carries neither x nor y: its flags would reach no sample");
    }
    check_no_shared_bits(r, status_bits, dbc_->source(), fail);
    by_frame_[key(m->id, m->extended)] = std::move(r);
  }
  if (status && !msgs.count(status->msg)) fail("status " + spec_.status + " is in a message carrying neither x nor y");
  for (int k = 0; k < 3; ++k)
    if (flag[k] && !msgs.count(flag[k]->msg))
      fail(std::string(flag_keys[k]) + " " + *flag_names[k] + " is in a message carrying neither x nor y");
  const DbcSignal* xs = by_frame_.at(key(x.msg->id, x.msg->extended)).samples[0].x;
  const auto where_of = [&](const char* k) {
    const auto at = spec_.key_where.find(k);
    return at != spec_.key_where.end() ? at->second : where;
  };
  x_scale_ = unit_to_g(xs->unit, "x " + x.msg->name + "." + xs->name, where_of("x"));
  if (y) {
    const DbcSignal* ys = by_frame_.at(key(y->msg->id, y->msg->extended)).samples[0].y;
    y_scale_ = unit_to_g(ys->unit, "y " + y->msg->name + "." + ys->name, where_of("y"));
  }
}

std::vector<CanFilter> DbcStreamDecoder::filters() const {
  std::vector<CanFilter> f;
  for (const auto& [k, r] : by_frame_)
    f.push_back({r.msg->id, r.msg->extended ? 0x1FFFFFFFu : 0x7FFu, r.msg->extended});
  return f;
}

bool DbcStreamDecoder::decode(const CanFdFrame& f, std::vector<StreamPart>& out, std::string* error) const {
  if (error) error->clear();
  if (f.error || f.rtr || (f.fd && spec_.classic_only)) return false;
  const auto it = by_frame_.find(key(f.id, f.extended));
  if (it == by_frame_.end()) return false;
  const Roles& r = it->second;
  const DbcMessage& m = *r.msg;
  const int len = f.len;
  if (len != m.dlc && !(m.dlc > 8 && len == canfd_round_up(m.dlc))) {
    if (error) *error = m.name + ": length " + std::to_string(len) + ", DBC says " + std::to_string(m.dlc);
    return true;
  }
  const std::span<const uint8_t> p(f.data.data(), static_cast<std::size_t>(std::min(len, 64)));
  // Multiplexing: a signal is present when it is not multiplexed or its value is selected.
  std::optional<int64_t> mux;
  for (const auto& s : m.signals)
    if (s.multiplexor) mux = static_cast<int64_t>(dbc_extract_raw(p, s.start, s.length, s.big_endian));
  auto present = [&](const DbcSignal* s) { return s && (!s->mux_value || (mux && *mux == *s->mux_value)); };
  if (!present(r.counter)) {
    if (error) *error = m.name + ": the multiplexer selects no counter";
    return true;
  }
  const uint32_t mask = counter_bits_ >= 32 ? 0xFFFFFFFFu : (uint32_t{1} << counter_bits_) - 1;
  const auto c0 = static_cast<uint32_t>(dbc_extract_raw(p, r.counter->start, r.counter->length, r.counter->big_endian));
  const int* bits[3] = {&spec_.filter_on_bit, &spec_.saturated_bit, &spec_.loop_fault_bit};
  for (std::size_t i = 0; i < r.samples.size(); ++i) {
    const Slot& sl = r.samples[i];
    const uint32_t seq = (c0 + static_cast<uint32_t>(i)) & mask;
    std::optional<uint8_t> st;
    if (present(sl.status)) {
      const uint64_t raw = dbc_extract_raw(p, sl.status->start, sl.status->length, sl.status->big_endian);
      uint8_t v = 0;
      for (int k = 0; k < 3; ++k)
        if (*bits[k] >= 0 && (raw >> *bits[k]) & 1u) v |= kFlagBits[k];
      st = v;
    }
    for (int k = 0; k < 3; ++k)
      if (present(sl.flag[k])) {
        uint8_t v = st.value_or(0);
        if (dbc_physical(*sl.flag[k], p) != 0) v |= kFlagBits[k];
        st = v;
      }
    auto part = [&](Channel c, const DbcSignal& s, double scale) {
      const double v = dbc_physical(s, p);
      const float g = static_cast<float>(v * scale);
      const bool outside = s.min < s.max && !(v >= s.min && v <= s.max);
      out.push_back({c, seq, st, g, outside || !std::isfinite(g)});
    };
    if (present(sl.x)) part(Channel::X, *sl.x, x_scale_);
    if (present(sl.y)) part(Channel::Y, *sl.y, y_scale_);
  }
  return true;
}

std::shared_ptr<const Dbc> rig_protocol_dbc() {
  static const auto db = std::make_shared<const Dbc>(Dbc::parse(kRigDutDbcText, "docs/rig-dut.dbc (built in)"));
  return db;
}

DbcStreamSpec rig_protocol_stream() {
  DbcStreamSpec s;
  s.counter = "DUT_STREAM_X.seq";
  s.x = "DUT_STREAM_X.x_g";
  s.y = "DUT_STREAM_Y.y_g";
  s.filter_on = "DUT_STREAM_X.status_filter_on";
  s.saturated = "DUT_STREAM_X.status_saturated";
  s.loop_fault = "DUT_STREAM_X.status_loop_fault";
  s.rate_hz = 1000;
  s.classic_only = true;
  return s;
}

std::string dut_dbc_path(const toml::table& dut) {
  const toml::node* dbc_node = dut.get("dbc");
  if (!dbc_node) return {};
  std::string path = cfg::get_string(dut, "dbc");
  // Relative to the hardware file's (or the profile's) folder, so a file and its DBC travel together.
  if (std::filesystem::path(path).is_relative() && dbc_node->source().path)
    path = (std::filesystem::path(cfg::relative_folder(*dbc_node)) / path).string();
  return path;
}

std::shared_ptr<const DbcStreamDecoder> stream_decoder_from_config(const toml::table& dut, const std::string& section) {
  const std::string st_name = "[" + section + ".stream]", dbc_name = "[" + section + "] dbc";
  const toml::node* dbc_node = dut.get("dbc");
  const toml::table* st = cfg::get_table(dut, "stream");
  if (!dbc_node) {
    if (st) throw ConfigError(cfg::where(*st) + ": " + st_name + " needs " + dbc_name + " = \"FILE\"");
    return std::make_shared<const DbcStreamDecoder>(rig_protocol_dbc(), rig_protocol_stream(), "rig protocol");
  }
  const std::string path = dut_dbc_path(dut);
  // A DBC that is not there is the hardware file's mistake: named at its line, with the path it
  // resolved to (relative to the hardware file, not the working directory).
  if (std::error_code ec; !std::filesystem::is_regular_file(path, ec))
    cfg::reject(*dbc_node, "dbc",
                (std::filesystem::exists(path, ec) ? "not a regular file: " : "no such file: ") + path);
  auto db = std::make_shared<const Dbc>(Dbc::parse_file(path));
  if (!st) throw ConfigError(cfg::where(*dbc_node) + ": " + dbc_name + " needs a " + st_name + " table naming its signals");
  cfg::check_keys(*st,
                  {"counter", "x", "y", "status", "filter_on_bit", "saturated_bit", "loop_fault_bit", "filter_on",
                   "saturated", "loop_fault", "samples_per_frame", "rate_hz"},
                  section + ".stream");
  DbcStreamSpec s;
  s.counter = cfg::get_string(*st, "counter");
  s.x = cfg::get_string(*st, "x");
  s.y = cfg::get_string(*st, "y", "");
  s.status = cfg::get_string(*st, "status", "");
  s.filter_on_bit = static_cast<int>(cfg::get_int(*st, "filter_on_bit", -1, 0, 63));
  s.saturated_bit = static_cast<int>(cfg::get_int(*st, "saturated_bit", -1, 0, 63));
  s.loop_fault_bit = static_cast<int>(cfg::get_int(*st, "loop_fault_bit", -1, 0, 63));
  s.filter_on = cfg::get_string(*st, "filter_on", "");
  s.saturated = cfg::get_string(*st, "saturated", "");
  s.loop_fault = cfg::get_string(*st, "loop_fault", "");
  s.samples_per_frame = static_cast<int>(cfg::get_int(*st, "samples_per_frame", 1, 1, 64));
  s.rate_hz = cfg::get_number(*st, "rate_hz", 1000.0, 1e-3, 1e6);
  for (auto&& [k, v] : *st) s.key_where[std::string(k.str())] = cfg::where(v) + ": " + st_name;
  auto dec = std::make_shared<const DbcStreamDecoder>(std::move(db), std::move(s), cfg::where(*st) + ": " + st_name);
  // With a command channel the link reads the protocol's own frames too; the stream's decoder
  // has the first claim on a frame, so a stream message on one of their ids would swallow the
  // DUT's responses or heartbeat (a review: ids 0x011 and 0x700 were accepted).
  if (cfg::get_bool(dut, "commands", true))
    for (const CanFilter& f : dec->filters()) {
      static constexpr std::pair<uint32_t, const char*> kProtocol[] = {
          {can_id::kCommand, "commands"}, {can_id::kResponse, "responses"}, {can_id::kLoopData, "loop-test data"},
          {can_id::kLoopEnd, "loop-test end markers"}, {can_id::kHeartbeat, "heartbeat"}};
      for (const auto& [id, what] : kProtocol)
        if (!f.extended && f.id == id) {
          char b[256];
          std::snprintf(b, sizeof b, ": a stream message on CAN id 0x%03X, which the DUT protocol uses for its %s "
                        "([%s] commands = true): move the stream or set commands = false", id, what, section.c_str());
          throw ConfigError(cfg::where(*st) + ": " + st_name + b);
        }
    }
  return dec;
}

}  // namespace rig::link
