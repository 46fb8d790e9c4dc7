#include "procedures/acceptance/state.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <span>
#include <stdexcept>

#include <fmt/format.h>

#include "rig/capture/capture.hpp"
#include "rig/core/errors.hpp"
#include "rig/executive/checkpoint_keys.hpp"

namespace rig::acceptance {

namespace {

constexpr double kNotStated = std::numeric_limits<double>::quiet_NaN();

// The keys to_json(Recorded) writes: every recording's object (a run, the in-run, the raw) has them.
constexpr std::array<std::string_view, 8> kRecordedKeys{"capture",    "n",        "lost",   "gaps",
                                                        "duplicates", "attempts", "mean_g", "mean_y_g"};

// Reading a JSON object field by field; every error names the field's path.
class Fields {
 public:
  Fields(const nlohmann::json& j, std::string path) : j_(j), path_(std::move(path)) {
    if (!j_.is_object()) fail("", "an object");
  }
  const nlohmann::json& at(const std::string& key) const {
    if (!j_.contains(key)) throw std::invalid_argument(path_ + "." + key + ": missing");
    return j_[key];
  }
  bool has(const std::string& key) const { return j_.contains(key) && !j_[key].is_null(); }
  std::string str(const std::string& key) const {
    const auto& v = at(key);
    if (!v.is_string()) fail(key, "a string", v);
    return v.get<std::string>();
  }
  double num(const std::string& key) const {
    const auto& v = at(key);
    if (!v.is_number()) fail(key, "a number", v);
    return v.get<double>();
  }
  std::optional<double> opt_num(const std::string& key) const {
    if (!has(key)) return std::nullopt;
    return num(key);
  }
  int64_t integer(const std::string& key) const {
    const auto& v = at(key);
    if (!v.is_number_integer()) fail(key, "an integer", v);
    return v.get<int64_t>();
  }
  uint64_t count(const std::string& key) const {
    const int64_t v = integer(key);
    if (v < 0) fail(key, "a count >= 0", at(key));
    return static_cast<uint64_t>(v);
  }
  Fields object(const std::string& key) const { return Fields(at(key), path_ + "." + key); }
  // A key this version does not write is refused (checkpoint_keys.hpp says why).
  // `also`: a shared key list (a recording's, kRecordedKeys) the object holds besides `keys`.
  void only(std::initializer_list<std::string_view> keys, std::span<const std::string_view> also = {}) const {
    if (const auto k = first_unknown_key(j_, std::span(keys.begin(), keys.size()), also))
      throw std::invalid_argument(path_ + "." + *k + ": " + std::string(kNotACheckpointKey));
  }
  const std::string& path() const { return path_; }
  [[noreturn]] void fail(const std::string& key, const std::string& expected, const nlohmann::json& found) const {
    throw std::invalid_argument((key.empty() ? path_ : path_ + "." + key) + ": expected " + expected + ", found " +
                                (found.is_primitive() ? found.dump() : std::string(found.type_name())));
  }

 private:
  [[noreturn]] void fail(const std::string& key, const std::string& expected) const { fail(key, expected, j_); }
  const nlohmann::json& j_;
  std::string path_;
};

Orientation orientation_from(const Fields& f, const std::string& key) {
  const std::string s = f.str(key);
  if (s == "U10") return Orientation::U10;
  if (s == "U20") return Orientation::U20;
  f.fail(key, "\"U10\" or \"U20\"", f.at(key));
}

Recorded recorded_from(const Fields& f) {
  Recorded r;
  r.capture = f.str("capture");
  r.samples = f.count("n");
  r.lost = f.count("lost");
  r.gaps = f.count("gaps");
  r.duplicates = f.has("duplicates") ? f.count("duplicates") : 0;  // older checkpoints lack it
  const uint64_t attempts = f.count("attempts");  // checked against the profile's retries with the capture
  if (attempts > 1000) f.fail("attempts", "a number of attempts (1 to the profile's retries + 1)", f.at("attempts"));
  r.attempts = static_cast<int>(attempts);
  // null (a channel whose mean was not finite) or absent (older checkpoints): not stated, and
  // taken from the capture when the state is restored (ProcedureState::check_capture).
  r.mean_x = f.has("mean_g") ? f.num("mean_g") : kNotStated;
  r.mean_y = f.has("mean_y_g") ? f.num("mean_y_g") : kNotStated;
  return r;
}

nlohmann::json opt_json(const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); }

std::vector<std::size_t> counts_from(const Fields& f, const std::string& key) {
  const nlohmann::json& a = f.at(key);
  if (!a.is_array()) f.fail(key, "an array of counts", a);
  std::vector<std::size_t> out;
  for (const auto& v : a) {
    if (!v.is_number_unsigned()) f.fail(key, "an array of counts", v);
    out.push_back(v.get<std::size_t>());
  }
  return out;
}

LoopRecord loop_record_from(const Fields& f) {
  LoopRecord r;
  f.only({"supported", "reason", "file", "rate_hz", "amplitude_g", "samples", "pre_samples", "saturated", "crc32"});
  const nlohmann::json& sup = f.at("supported");
  if (!sup.is_boolean()) f.fail("supported", "true or false", sup);
  r.supported = sup.get<bool>();
  if (!r.supported) {
    r.reason = f.str("reason");
    return r;
  }
  r.file = f.str("file");
  r.rate_hz = f.num("rate_hz");
  r.amplitude_g = f.num("amplitude_g");
  r.samples = counts_from(f, "samples");
  r.pre_samples = counts_from(f, "pre_samples");
  const nlohmann::json& sat = f.at("saturated");
  if (!sat.is_array()) f.fail("saturated", "an array of true/false", sat);
  for (const auto& v : sat) {
    if (!v.is_boolean()) f.fail("saturated", "an array of true/false", v);
    r.saturated.push_back(v.get<bool>());
  }
  const uint64_t crc = f.count("crc32");
  if (crc > 0xffffffffu) f.fail("crc32", "a CRC-32", f.at("crc32"));
  r.crc32 = static_cast<uint32_t>(crc);
  if (r.pre_samples.size() != r.samples.size() || r.saturated.size() != r.samples.size())
    f.fail("samples", "one count per step, as pre_samples and saturated have", f.at("samples"));
  if (!(r.rate_hz > 0)) f.fail("rate_hz", "a rate > 0", f.at("rate_hz"));
  return r;
}

}  // namespace

nlohmann::json to_json(const Recorded& r) {
  return {{"capture", r.capture}, {"n", r.samples},       {"lost", r.lost},     {"gaps", r.gaps},
          {"duplicates", r.duplicates}, {"attempts", r.attempts}, {"mean_g", r.mean_x}, {"mean_y_g", r.mean_y}};
}

std::vector<std::string> DutState::captures() const {
  std::vector<std::string> c;
  for (const auto& [i, r] : runs) c.push_back(r.rec.capture);
  if (in_run) c.push_back(in_run->capture);
  if (raw) c.push_back(raw->capture);
  return c;
}

nlohmann::json to_json(const DutState& s) {
  nlohmann::json j = nlohmann::json::object();
  if (s.dut) {
    j["serial"] = s.dut->serial;  // read by checkpoints of earlier versions
    j["dut"] = {{"serial", s.dut->serial}, {"firmware", s.dut->firmware}, {"temperature_c", opt_json(s.dut->temperature_c)}};
    if (!s.dut->skipped.empty()) {
      nlohmann::json sk = nlohmann::json::array();
      for (const SkippedStep& k : s.dut->skipped) sk.push_back({{"step", k.step}, {"reason", k.reason}});
      j["dut"]["skipped"] = sk;
    }
  }
  if (!s.runs.empty()) {
    nlohmann::json runs = nlohmann::json::object();
    for (const auto& [i, r] : s.runs) {
      nlohmann::json e = to_json(r.rec);
      e["index"] = r.index;
      e["orientation"] = to_string(r.orientation);
      runs[std::to_string(i)] = e;
    }
    j["runs"] = runs;
  }
  if (s.bias) j["bias"] = {{"bias", s.bias->bias}, {"base_error", s.bias->base_error}, {"sign_u10", s.bias->sign_u10}};
  if (s.in_run) j["in_run"] = to_json(*s.in_run);
  if (s.in_run_blocks) {
    nlohmann::json blocks = nlohmann::json::array();
    for (const auto& b : *s.in_run_blocks)
      blocks.push_back({{"block_s", b.block_s}, {"means_g", b.means_g}, {"b_g", opt_json(b.b_g)}});
    j["in_run"]["blocks"] = blocks;
  }
  if (s.raw) j["raw"] = to_json(*s.raw);
  if (s.analysis) j["analysis"] = *s.analysis;
  if (s.loop_test) j["loop_test"] = to_json(*s.loop_test);
  if (s.loop) j["loop"] = *s.loop;
  if (s.device_time_s) j["device_time_s"] = *s.device_time_s;
  return j;
}

DutState dut_state_from_json(const nlohmann::json& j) {
  const Fields f(j, "state");
  f.only({"serial", "dut", "runs", "bias", "in_run", "raw", "analysis", "loop_test", "loop", "device_time_s"});
  DutState s;
  if (f.has("dut")) {
    const Fields d = f.object("dut");
    d.only({"serial", "firmware", "temperature_c", "skipped"});
    s.dut = DutIdentity{d.str("serial"), d.str("firmware"), d.opt_num("temperature_c"), {}};
    if (d.has("skipped")) {
      const nlohmann::json& sk = d.at("skipped");
      if (!sk.is_array()) d.fail("skipped", "an array", sk);
      for (std::size_t i = 0; i < sk.size(); ++i) {
        const Fields k(sk[i], d.path() + ".skipped[" + std::to_string(i) + "]");
        k.only({"step", "reason"});
        s.dut->skipped.push_back({k.str("step"), k.str("reason")});
      }
    }
  }
  if (f.has("runs")) {
    const Fields rs = f.object("runs");
    for (const auto& [k, v] : f.at("runs").items()) {
      const Fields r(v, rs.path() + "." + k);
      r.only({"index", "orientation"}, kRecordedKeys);
      RunMean m;
      m.index = static_cast<std::size_t>(r.count("index"));
      if (std::to_string(m.index) != k) r.fail("index", "the run's key " + k, r.at("index"));
      m.orientation = orientation_from(r, "orientation");
      m.rec = recorded_from(r);
      if (!r.has("mean_g")) r.fail("mean_g", "a number", nlohmann::json(nullptr));
      s.runs[m.index] = m;
    }
  }
  if (f.has("bias")) {
    const Fields b = f.object("bias");
    b.only({"bias", "base_error", "sign_u10"});
    BiasState bs{b.num("bias"), b.num("base_error"), static_cast<int>(b.integer("sign_u10"))};
    if (bs.sign_u10 != 1 && bs.sign_u10 != -1) b.fail("sign_u10", "+1 or -1", b.at("sign_u10"));
    s.bias = bs;
  }
  if (f.has("in_run")) {
    const Fields ir = f.object("in_run");
    ir.only({"blocks"}, kRecordedKeys);
    if (ir.has("capture")) s.in_run = recorded_from(ir);
    if (ir.has("blocks")) {
      const auto& arr = ir.at("blocks");
      if (!arr.is_array()) ir.fail("blocks", "an array", arr);
      std::vector<GostBlock> blocks;
      for (std::size_t i = 0; i < arr.size(); ++i) {
        const Fields b(arr[i], ir.path() + ".blocks[" + std::to_string(i) + "]");
        b.only({"block_s", "means_g", "b_g"});
        GostBlock g;
        g.block_s = b.num("block_s");
        const auto& means = b.at("means_g");
        if (!means.is_array()) b.fail("means_g", "an array of numbers", means);
        for (const auto& m : means) {
          if (!m.is_number()) b.fail("means_g", "an array of numbers", m);
          g.means_g.push_back(m.get<double>());
        }
        g.b_g = b.opt_num("b_g");
        blocks.push_back(std::move(g));
      }
      s.in_run_blocks = std::move(blocks);
    }
  }
  if (f.has("raw")) {
    const Fields raw = f.object("raw");
    raw.only({}, kRecordedKeys);
    s.raw = recorded_from(raw);
  }
  if (f.has("analysis")) {
    if (!f.at("analysis").is_object()) f.fail("analysis", "an object", f.at("analysis"));
    s.analysis = f.at("analysis");
  }
  if (f.has("loop_test")) s.loop_test = loop_record_from(f.object("loop_test"));
  if (f.has("loop")) {
    if (!f.at("loop").is_object()) f.fail("loop", "an object", f.at("loop"));
    s.loop = f.at("loop");
  }
  s.device_time_s = f.opt_num("device_time_s");  // absent in checkpoints before it was kept
  // Bounded far above any procedure (a 50-hour capture is 1.8e5 s): 1e300 s is no device time.
  if (s.device_time_s && !(std::isfinite(*s.device_time_s) && *s.device_time_s >= 0 && *s.device_time_s <= 1e9))
    f.fail("device_time_s", "a device time in [0, 1e9] s", f.at("device_time_s"));
  if (s.loop_test && !s.device_time_s)  // written with it by every version that writes loop_test
    f.fail("device_time_s", "a device time (the state has loop_test)", nlohmann::json(nullptr));
  return s;
}

nlohmann::json ProcedureState::save() const { return to_json(slots_.at(0)); }

// A record named by the state must be the recording its field says, as record.cpp left it:
// its own capture (the field's phase id, orientation, the profile's rate, the state's DUT),
// closed by the writer and undamaged, holding exactly the samples a recording of that length
// holds, with the record's means (summed here as record.cpp sums them, so equal to the last bit),
// a sequence counter that only goes forward, and its losses within the profile's
// max_lost_samples and at least what the counter shows. The phases that compute from records
// read these records: a checkpoint that contradicts its captures is refused, never believed.
void ProcedureState::check_capture(Recorded& r, const std::string& field, const std::string& run_dir,
                                   const Recording& want) const {
  const std::string rel = capture_rel(want.phase_id), path = run_dir + "/" + rel;
  if (r.capture != rel)
    throw std::invalid_argument(field + ".capture: \"" + r.capture + "\" is not this recording's capture (" + rel + ")");
  if (!std::filesystem::exists(path)) throw std::invalid_argument(field + ".capture: " + path + " is missing");
  if (!std::filesystem::is_regular_file(path))
    throw std::invalid_argument(field + ".capture: " + path + " is not a regular file");
  const uint64_t planned = planned_samples(profile_, want.seconds);
  if (r.samples != planned)
    throw std::invalid_argument(field + ".n: " + std::to_string(r.samples) + " samples, but a recording of " +
                                fmt::format("{:g} s at {:g} Hz", want.seconds, profile_.rate_hz) + " holds " +
                                std::to_string(planned));
  if (r.attempts < 1 || r.attempts > profile_.retries + 1)
    throw std::invalid_argument(field + ".attempts: " + std::to_string(r.attempts) + ", but a kept recording took 1 to " +
                                std::to_string(profile_.retries + 1) + " attempts (the profile's retries + 1)");
  if (r.lost > profile_.max_lost_samples)
    throw std::invalid_argument(field + ".lost: " + std::to_string(r.lost) + " exceeds the profile's max_lost_samples (" +
                                std::to_string(profile_.max_lost_samples) + "): such a recording is retried, not kept");
  uint64_t n = 0, lost = 0, gaps = 0;
  double sx = 0, sy = 0;
  try {
    capture::Reader rd(path);
    const capture::Header& h = rd.header();
    auto header = [&](const std::string& key, const std::string& found, const std::string& expected) {
      if (found != expected)
        throw std::invalid_argument(field + ".capture: " + path + "'s header says " + key + " '" + found + "', not '" +
                                    expected + "'");
    };
    header("phase", h.phase, want.phase_id);
    header("orientation", h.orientation, to_string(want.orientation));
    header("serial", h.serial, want.serial);
    if (h.rate_hz != profile_.rate_hz)
      throw std::invalid_argument(field + ".capture: " + path + " was recorded at " + fmt::format("{:g}", h.rate_hz) +
                                  " Hz, the profile says " + fmt::format("{:g}", profile_.rate_hz));
    if (rd.max_samples() < r.samples)
      throw std::invalid_argument(field + ".n: " + std::to_string(r.samples) + " samples recorded, but " + path +
                                  " is too short to hold them");
    std::vector<Sample> buf(4096);
    uint32_t prev = 0;
    for (std::size_t got; (got = rd.read(buf)) > 0;)
      for (std::size_t i = 0; i < got; ++i) {
        const Sample& v = buf[i];
        if (n > 0 && v.seq != prev + 1u) {
          const std::optional<uint32_t> skipped = capture::lost_between(prev, v.seq);
          if (!skipped)
            throw std::invalid_argument(field + ".capture: " + path + "'s sequence counter goes back at sample " +
                                        std::to_string(n) + " (" + std::to_string(prev) + " then " +
                                        std::to_string(v.seq) + "): not a recording's order");
          ++gaps;
          lost += *skipped;
        }
        prev = v.seq;
        sx += v.x_g;  // float into double, in order: record.cpp's sum
        sy += v.y_g;
        ++n;
      }
    if (!rd.recovery().complete)
      throw std::invalid_argument(field + ".capture: " + rd.recovery().summary(path) +
                                  " (a completed recording's writer closed it)");
  } catch (const ConfigError& e) {
    throw std::invalid_argument(field + ".capture: " + e.what());
  }
  if (n != r.samples)
    throw std::invalid_argument(field + ".n: " + std::to_string(r.samples) + " samples recorded, but " + path +
                                " holds " + std::to_string(n));
  const double mx = n ? sx / static_cast<double>(n) : 0, my = n ? sy / static_cast<double>(n) : 0;
  // A mean the checkpoint does not state (null: not finite when recorded, or an older
  // checkpoint without it) is the capture's; a stated one must be it to the last bit.
  auto same_mean = [&](const char* key, double& recorded, double computed) {
    if (std::isnan(recorded)) recorded = computed;
    else if (recorded != computed)
      throw std::invalid_argument(field + "." + key + ": " + fmt::format("{:.17g}", recorded) + " contradicts " +
                                  path + ", whose samples' mean is " + fmt::format("{:.17g}", computed));
  };
  same_mean("mean_g", r.mean_x, mx);
  same_mean("mean_y_g", r.mean_y, my);
  r.written = stamp_of(path);  // as checked: the run's end compares the file with it
  if (lost > r.lost || gaps > r.gaps)
    throw std::invalid_argument(field + ".lost: " + std::to_string(r.lost) + " samples lost in " +
                                std::to_string(r.gaps) + " gap(s) recorded, but " + path + "'s sequence counter skips " +
                                std::to_string(lost) + " in " + std::to_string(gaps));
}

std::string ProcedureState::recording_problem(const std::string& file, const std::string& run_dir) const {
  DutState s = slots_.at(0);  // a copy: the checks fill in what they read
  try {
    for (auto& [idx, r] : s.runs)
      if (r.rec.capture == file && idx >= 1 && idx <= profile_.order.size())
        check_capture(r.rec, "state.runs." + std::to_string(idx), run_dir, run_recording(idx, s.serial()));
    if (s.in_run && s.in_run->capture == file) check_capture(*s.in_run, "state.in_run", run_dir, in_run_recording(s.serial()));
    if (s.raw && s.raw->capture == file) check_capture(*s.raw, "state.raw", run_dir, raw_recording(s.serial()));
    if (s.loop_test && s.loop_test->supported && s.loop_test->file == file) check_loop_record(*s.loop_test, run_dir);
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

void ProcedureState::restore(const nlohmann::json& j, const std::vector<std::string>& completed,
                             const std::string& run_dir) {
  DutState s = dut_state_from_json(j);
  auto is_done = [&](const std::string& id) { return std::find(completed.begin(), completed.end(), id) != completed.end(); };
  // Each completed phase must have left its part (a phase's id tells which), and no part may
  // be there that no completed phase wrote (it would reach the passport's list of captures).
  auto need = [](bool present, const std::string& field, const std::string& phase) {
    if (!present)
      throw std::invalid_argument(field + ": missing, but phase '" + phase + "' that writes it is marked completed");
  };
  auto unwritten = [&](bool present, const std::string& field, const std::string& phase) {
    if (present && !is_done(phase))
      throw std::invalid_argument(field + ": present, but phase '" + phase + "' that writes it is not completed");
  };
  for (const auto& [idx, r] : s.runs)
    if (idx < 1 || idx > profile_.order.size() || !is_done(run_phase_id(idx, profile_.order[idx - 1])))
      throw std::invalid_argument("state.runs." + std::to_string(idx) + ": present, but no completed phase records it");
  unwritten(s.bias.has_value(), "state.bias", "bias");
  unwritten(s.in_run.has_value(), "state.in_run", "in-run");
  unwritten(s.in_run_blocks.has_value(), "state.in_run.blocks", "in-run-b");
  unwritten(s.raw.has_value(), "state.raw", "raw");
  unwritten(s.analysis.has_value(), "state.analysis", "allan");
  // A checkpoint written before the loop test kept its records: `loop` completed with only its
  // figures. Those figures are not taken; the loop test runs again (holds("loop") is false).
  loop_figures_only_ = is_done("loop") && !is_done("loop-figures") && !s.loop_test && s.loop;
  if (loop_figures_only_) s.loop.reset();
  // A loop test the DUT did not run recorded nothing to keep: a resume asks the DUT again rather
  // than taking "not supported" (and its reason) from the file (no DUT is measured twice so).
  loop_not_run_ = is_done("loop") && s.loop_test && !s.loop_test->supported;
  unwritten(s.loop_test.has_value(), "state.loop_test", "loop");
  unwritten(s.loop.has_value(), "state.loop", "loop-figures");
  // The DUT the recordings were made from: bring-up's identity, which a resume's bring-up and
  // every capture's header are checked against.
  const bool recorded = !s.runs.empty() || s.in_run || s.raw;
  if (recorded && s.serial().empty())
    throw std::invalid_argument(std::string("state.dut") + (s.dut ? ".serial: empty" : ": missing") +
                                ", but recordings are marked completed (the DUT they were made from)");
  for (const std::string& id : completed) {
    if (id.rfind("run", 0) == 0 && id.find('-') != std::string::npos) {  // runNN-Uxx
      const std::size_t idx = std::stoul(id.substr(3, id.find('-') - 3));
      need(s.runs.count(idx) > 0, "state.runs." + std::to_string(idx), id);
      RunMean& r = s.runs.at(idx);
      if (idx > profile_.order.size() || r.orientation != profile_.order[idx - 1])
        throw std::invalid_argument("state.runs." + std::to_string(idx) + ".orientation: " +
                                    to_string(r.orientation) + " does not match the profile's order");
      check_capture(r.rec, "state.runs." + std::to_string(idx), run_dir, run_recording(idx, s.serial()));
    } else if (id == "bias") {
      need(s.bias.has_value(), "state.bias", id);
    } else if (id == "in-run") {
      need(s.in_run.has_value(), "state.in_run", id);
      check_capture(*s.in_run, "state.in_run", run_dir, in_run_recording(s.serial()));
    } else if (id == "in-run-b") {
      need(s.in_run_blocks.has_value(), "state.in_run.blocks", id);
    } else if (id == "raw") {
      need(s.raw.has_value(), "state.raw", id);
      check_capture(*s.raw, "state.raw", run_dir, raw_recording(s.serial()));
    } else if (id == "allan") {
      need(s.analysis.has_value(), "state.analysis", id);
    } else if (id == "loop") {
      if (loop_figures_only_) continue;
      need(s.loop_test.has_value(), "state.loop_test", id);
      check_loop_record(*s.loop_test, run_dir);  // before any device opens, as the captures
    } else if (id == "loop-figures") {
      need(s.loop.has_value(), "state.loop", id);
    }
  }
  slots_.at(0) = std::move(s);
}

void ProcedureState::forget(const std::string& id) {
  DutState& s = slots_.at(0);
  if (id.rfind("run", 0) == 0 && id.find('-') != std::string::npos) s.runs.erase(std::stoul(id.substr(3, id.find('-') - 3)));
  else if (id == "bias") s.bias.reset();
  else if (id == "in-run") s.in_run.reset();
  else if (id == "in-run-b") s.in_run_blocks.reset();
  else if (id == "raw") s.raw.reset();
  else if (id == "allan") s.analysis.reset();
  else if (id == "loop") s.loop_test.reset();
  else if (id == "loop-figures") s.loop.reset();
}

bool ProcedureState::holds(const std::string& id) const {
  return !(id == "loop" && (loop_figures_only_ || loop_not_run_));
}

}  // namespace rig::acceptance
