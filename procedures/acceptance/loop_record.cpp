#include "procedures/acceptance/loop_record.hpp"

#include <charconv>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include <fmt/format.h>
#include <zlib.h>

#include "rig/core/errors.hpp"

namespace rig::acceptance {

namespace {

constexpr const char* kFirstLine = "# rig loop test: ";
constexpr const char* kSaturatedLine = "# steps in which the DUT's loop saturated: ";
// The same line as written before 2026-12-07 (a run folder of then is resumed and verified).
constexpr std::string_view kSaturatedLineBefore = "# steps in which the DUT's PWM saturated: ";

// The saturation line's list: the 1-based steps flagged, "none" without any.
std::string saturated_steps(const std::vector<bool>& flags) {
  std::string s;
  for (std::size_t k = 0; k < flags.size(); ++k)
    if (flags[k]) s += (s.empty() ? "" : ", ") + std::to_string(k + 1);
  return s.empty() ? "none" : s;
}

}  // namespace

nlohmann::json to_json(const LoopRecord& r) {
  if (!r.supported) return {{"supported", false}, {"reason", r.reason}};
  return {{"supported", true}, {"file", r.file},       {"rate_hz", r.rate_hz},         {"amplitude_g", r.amplitude_g},
          {"samples", r.samples}, {"pre_samples", r.pre_samples}, {"saturated", r.saturated}, {"crc32", r.crc32}};
}

uint32_t crc32_of(const std::string& bytes) {
  uLong c = crc32(0L, Z_NULL, 0);
  for (std::size_t at = 0; at < bytes.size();) {  // zlib takes uInt lengths
    const std::size_t n = std::min<std::size_t>(bytes.size() - at, 1u << 30);
    c = crc32(c, reinterpret_cast<const Bytef*>(bytes.data() + at), static_cast<uInt>(n));
    at += n;
  }
  return static_cast<uint32_t>(c);
}

LoopRecord loop_record_of(const LoopTestResponse& r, const std::string& csv) {
  LoopRecord rec;
  rec.supported = true;
  rec.file = kLoopTestFile;
  rec.rate_hz = r.rate_hz;
  rec.amplitude_g = r.amplitude_g;
  for (const LoopStepRecord& st : r.steps) {
    rec.samples.push_back(st.x.size());
    rec.pre_samples.push_back(st.pre_samples);
    rec.saturated.push_back(st.saturated);
  }
  rec.crc32 = crc32_of(csv);
  return rec;
}

std::string loop_test_csv(const LoopTestResponse& r) {
  std::vector<bool> saturated;
  for (const LoopStepRecord& st : r.steps) saturated.push_back(st.saturated);
  std::string s = fmt::format(
      "{}{} step(s) of {} g test torque inside the DUT's loop, recorded at {} Hz\n"
      "# x_g: the loop's output; y_g: the same through the DUT's output filter while it is on (else as x_g); t_s "
      "from the step\n"
      "{}{}\n"
      "step,index,t_s,x_g,y_g\n",
      kFirstLine, r.steps.size(), r.amplitude_g, r.rate_hz, kSaturatedLine, saturated_steps(saturated));
  for (std::size_t k = 0; k < r.steps.size(); ++k) {
    const LoopStepRecord& st = r.steps[k];
    // {} is the shortest decimal that reads back to the same double: loop-figures, which reads
    // this file, computes from exactly what the DUT sent.
    for (std::size_t i = 0; i < st.x.size(); ++i)
      s += fmt::format("{},{},{:.6g},{},{}\n", k + 1, i,
                       (static_cast<double>(i) - static_cast<double>(st.pre_samples)) / r.rate_hz, st.x[i], st.y[i]);
  }
  return s;
}

std::string loop_test_bytes(const std::string& path, const LoopRecord& rec) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (!in) throw ConfigError(path + ": cannot read the loop test's records");
  const uint32_t crc = crc32_of(bytes.str());
  if (crc != rec.crc32)
    throw ConfigError(fmt::format("state.loop_test.crc32: {} does not match {} (CRC-32 {}): the loop test's records "
                                  "were changed since they were recorded",
                                  rec.crc32, path, crc));
  return bytes.str();
}

LoopTestResponse read_loop_test_csv(const std::string& path, const LoopRecord& rec) {
  return parse_loop_test_csv(loop_test_bytes(path, rec), path, rec);
}

LoopTestResponse parse_loop_test_csv(const std::string& text, const std::string& path, const LoopRecord& rec) {
  std::istringstream in(text);
  std::size_t line_no = 0;
  auto bad = [&](const std::string& what) { return ConfigError(fmt::format("{}:{}: {}", path, line_no, what)); };
  LoopTestResponse r;
  r.supported = true;
  r.rate_hz = rec.rate_hz;
  r.amplitude_g = rec.amplitude_g;
  bool header = false, stated = false, saturation_stated = false;
  std::vector<std::size_t> before_step;  // per step: rows with t_s < 0
  auto number_in = [&](std::string_view& rest, const char* name) {
    double d = 0;
    const auto [end, ec] = std::from_chars(rest.data(), rest.data() + rest.size(), d);
    if (ec != std::errc()) throw bad(fmt::format("{}: expected a number at '{}'", name, rest));
    rest.remove_prefix(static_cast<std::size_t>(end - rest.data()));
    return d;
  };
  auto expect_text = [&](std::string_view& rest, std::string_view want) {
    if (rest.substr(0, want.size()) != want) throw bad(fmt::format("expected '{}' at '{}'", want, rest));
    rest.remove_prefix(want.size());
  };
  auto integer = [&](std::string_view v, const char* name) {
    std::size_t n = 0;
    const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
    if (ec != std::errc() || end != v.data() + v.size())
      throw bad(fmt::format("{} '{}' is not a whole number", name, v));
    return n;
  };
  auto number = [&](std::string_view v, const char* name) {
    double d = 0;
    const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), d);
    if (ec != std::errc() || end != v.data() + v.size()) throw bad(fmt::format("{} '{}' is not a number", name, v));
    return d;
  };
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    if (!header && line.rfind(kFirstLine, 0) == 0) {
      // What the records are: every figure depends on the amplitude and the rate, so the file,
      // not only the checkpoint, states them (a checkpoint that contradicts it is refused).
      std::string_view rest = std::string_view(line).substr(std::string_view(kFirstLine).size());
      const double steps = number_in(rest, "steps");
      expect_text(rest, " step(s) of ");
      const double amplitude = number_in(rest, "amplitude");
      expect_text(rest, " g test torque inside the DUT's loop, recorded at ");
      const double rate = number_in(rest, "rate");
      expect_text(rest, " Hz");
      if (!rest.empty()) throw bad(fmt::format("unexpected '{}' after the rate", rest));
      if (steps != static_cast<double>(rec.samples.size()) || amplitude != rec.amplitude_g || rate != rec.rate_hz)
        throw bad(fmt::format("the file states {} step(s) of {} g at {} Hz; the loop test recorded {} of {} g at {} Hz",
                              steps, amplitude, rate, rec.samples.size(), rec.amplitude_g, rec.rate_hz));
      stated = true;
      continue;
    }
    const std::string_view sat_line = line.starts_with(kSaturatedLineBefore) ? kSaturatedLineBefore : kSaturatedLine;
    if (!header && line.starts_with(sat_line)) {
      const std::string listed = line.substr(sat_line.size());
      if (listed != saturated_steps(rec.saturated))
        throw bad(fmt::format("the file states the loop saturated in steps '{}'; the loop test recorded '{}'", listed,
                              saturated_steps(rec.saturated)));
      saturation_stated = true;
      continue;
    }
    if (line.empty() || line[0] == '#') continue;
    if (!header) {
      if (line != "step,index,t_s,x_g,y_g")
        throw bad("expected the header 'step,index,t_s,x_g,y_g', found '" + line + "'");
      header = true;
      continue;
    }
    std::vector<std::string_view> f;
    for (std::size_t at = 0;;) {
      const std::size_t comma = line.find(',', at);
      f.emplace_back(std::string_view(line).substr(at, comma == std::string::npos ? std::string::npos : comma - at));
      if (comma == std::string::npos) break;
      at = comma + 1;
    }
    if (f.size() != 5) throw bad(fmt::format("expected 5 fields (step,index,t_s,x_g,y_g), found {}: '{}'", f.size(), line));
    const std::size_t step = integer(f[0], "step"), index = integer(f[1], "index");
    if (step == r.steps.size() + 1) {  // the next step begins
      if (step > rec.samples.size())
        throw bad(fmt::format("step {}: the loop test recorded {} step(s)", step, rec.samples.size()));
      r.steps.emplace_back();
      before_step.push_back(0);
    } else if (step != r.steps.size() || step == 0) {
      throw bad(fmt::format("step {} after step {}: the steps are numbered 1, 2, ... in order", step, r.steps.size()));
    }
    LoopStepRecord& st = r.steps.back();
    if (index != st.x.size())
      throw bad(fmt::format("index {} in step {}: expected {} (the samples of a step in order from 0)", index, step,
                            st.x.size()));
    if (number(f[2], "t_s") < 0) ++before_step.back();
    st.x.push_back(number(f[3], "x_g"));
    st.y.push_back(number(f[4], "y_g"));
  }
  if (!header) throw bad("no header 'step,index,t_s,x_g,y_g'");
  if (!stated || !saturation_stated)
    throw bad(fmt::format("the comment lines '{}...' and '{}...' are missing", kFirstLine, kSaturatedLine));
  if (r.steps.size() != rec.samples.size())
    throw bad(fmt::format("{} step(s) in the file, but the loop test recorded {}", r.steps.size(), rec.samples.size()));
  for (std::size_t k = 0; k < r.steps.size(); ++k) {
    LoopStepRecord& st = r.steps[k];
    if (st.x.size() != rec.samples[k] || before_step[k] != rec.pre_samples[k])
      throw bad(fmt::format("step {}: {} samples, {} before the step; the loop test recorded {}, {} before the step",
                            k + 1, st.x.size(), before_step[k], rec.samples[k], rec.pre_samples[k]));
    st.pre_samples = rec.pre_samples[k];
    st.saturated = rec.saturated[k];
  }
  return r;
}

void check_loop_record(const LoopRecord& r, const std::string& run_dir) {
  if (!r.supported) {
    // Not run, so nothing recorded: records in the folder contradict it (the design model's
    // figures would stand in for a measured DUT's).
    if (std::filesystem::exists(std::filesystem::symlink_status(run_dir + "/" + kLoopTestFile)))
      throw std::invalid_argument(std::string("state.loop_test.supported: false, but ") + run_dir + "/" + kLoopTestFile +
                                  " holds a loop test's records");
    return;
  }
  if (r.file != kLoopTestFile)
    throw std::invalid_argument("state.loop_test.file: \"" + r.file + "\" is not the loop test's records (" +
                                kLoopTestFile + ")");
  const std::string path = run_dir + "/" + r.file;
  if (!std::filesystem::is_regular_file(path))
    throw std::invalid_argument("state.loop_test.file: " + path +
                                (std::filesystem::exists(path) ? " is not a regular file" : " is missing"));
  std::string bytes;
  try {
    bytes = loop_test_bytes(path, r);
  } catch (const ConfigError& e) {
    throw std::invalid_argument(e.what());  // names state.loop_test.crc32
  }
  try {
    parse_loop_test_csv(bytes, path, r);
  } catch (const ConfigError& e) {
    throw std::invalid_argument(std::string("state.loop_test: ") + e.what());
  }
}

}  // namespace rig::acceptance
