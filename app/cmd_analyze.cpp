// `rig analyze FILE`: overlapping Allan deviation with confidence bounds, noise terms (the
// paper's polynomial method and a weighted fit), Welch PSD with peaks; JSON per docs/contracts.md,
// SVG plots on request. Large float64 files are streamed (bounded memory, both cores).
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <exception>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <cstdint>
#include <cmath>
#include <numbers>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "analysis/json.hpp"
#include "rig/core/number_text.hpp"
#include "app/analyze_input.hpp"
#include "rig/core/escape.hpp"
#include "app/output_file.hpp"
#include "analysis/allan.hpp"
#include "analysis/noise_terms.hpp"
#include "analysis/options.hpp"
#include "analysis/psd.hpp"
#include "analysis/theo.hpp"
#include "rig/report/svg_plot.hpp"
#include "rig/capture/capture.hpp"
#include "app/commands.hpp"
#include "app/whole_number.hpp"
#include "rig/core/errors.hpp"

namespace rig::cli {

namespace {

namespace an = rig::analysis;
using nlohmann::json;

// A deviation no larger than this many units in the last place of the values is their rounding.
constexpr double kRoundingUlps = 16;

// Whether every deviation computed is 0 or the rounding of the values (a constant record, a
// straight phase line): nothing there is noise. A review found a phase line (values up to 1e-4)
// with OADEV 6e-21 given noise types, bounds, noise terms and PSD peaks. scale: the values'
// largest magnitude (a constant's or a line's: its first or last value). Rounding moves each
// value by about one unit in the last place, so a second difference by a few: in the values'
// units, dev for frequency data and dev * tau (the phase's) for phase data.
bool no_noise_above_rounding(const std::vector<std::vector<an::DevPoint>>& devs, double scale, an::DataKind data) {
  // The unit in the last place of `scale` itself (epsilon * scale was up to two of them: 1e6 g
  // with white noise of 26 ulps read as constant, a review).
  const double ulp = std::nextafter(scale, std::numeric_limits<double>::infinity()) - scale;
  const double rounding = kRoundingUlps * ulp;
  for (const auto& d : devs)
    for (const auto& p : d)
      if ((data == an::DataKind::Phase ? p.dev * p.tau_s : p.dev) > rounding) return false;
  return !devs.empty();
}

// The largest magnitude of the record's first and last values: its scale where it is a
// constant or a line, the only records no_noise_above_rounding can find noiseless.
double end_value_scale(const an::ChunkSource& src) {
  double first = 0, last = 0;
  src.read_at(0, std::span<double>(&first, 1));
  src.read_at(src.size() - 1, std::span<double>(&last, 1));
  return std::max(std::fabs(first), std::fabs(last));
}

// The largest magnitude among about 4096 values spread evenly over the record (its ends included):
// enough to tell a record of tiny values from one of zeros, without another pass over 1.44 GB.
double sampled_magnitude(const an::ChunkSource& src) {
  const std::uint64_t n = src.size();
  const std::uint64_t step = std::max<std::uint64_t>(1, n / 4096);
  double big = 0, x = 0;
  for (std::uint64_t i = 0; i < n; i += step) {
    src.read_at(i, std::span<double>(&x, 1));
    big = std::max(big, std::fabs(x));
  }
  src.read_at(n - 1, std::span<double>(&x, 1));
  return std::max(big, std::fabs(x));
}

// OADEV as --no-bounds reports it and fits the noise terms to: no noise type, no EDF, no bounds
// (the pass identified the noise for the total family's bias removal only).
std::vector<an::DevPoint> without_identification(std::vector<an::DevPoint> pts) {
  for (an::DevPoint& p : pts) p.lo = p.hi = p.edf = 0, p.alpha = p.edf_alpha = 0;
  return pts;
}

// Whether a long-tau statistic divides by a noise-type bias (MTOT, TTOT, HTOT: theo.hpp tot_bias).
bool has_noise_bias(an::LongTau t) { return t == an::LongTau::MTOT || t == an::LongTau::TTOT || t == an::LongTau::HTOT; }

// The bounds' confidence in a table's header: the default one sigma as 0.682689, any other level
// as typed.
std::string confidence_shown(double c) {
  if (c != an::kOneSigma) return shortest_text(c);
  char b[32];
  std::snprintf(b, sizeof b, "%g", c);
  return b;
}

struct Args {
  std::string file, input = "auto", data = "freq", taus = an::AnalysisOptions{}.taus, dev = "oadev";
  std::optional<std::string> channel;  // captures only: x (default) or y
  std::optional<std::string> gaps;    // captures only: join (default) | longest | stop
  std::string json_out, svg_dir, window = "hann";
  std::optional<double> rate;
  std::string rate_text;  // --rate as typed, for its messages (2000000 read "2e+06": a technician's review)
  double confidence = an::AnalysisOptions{}.confidence;
  bool no_bounds = false, no_psd = false, no_oadev = false, no_work_limit = false;
  unsigned threads = 0;
  std::size_t memory_mib = 384;
  std::optional<std::size_t> segment;  // none: the automatic length
  double overlap = 0.5;
};


std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4e", v);
  return b;
}

void print_term(std::ostream& o, const char* name, const an::Term& t, double (*to_hours)(double), const char* hu) {
  o << "  " << name << " = ";
  if (!t.value) {
    o << "null (" << t.reason << ")\n";
    return;
  }
  o << fmt(*t.value) << ' ' << t.unit;
  if (t.lo && t.hi) o << "  [" << fmt(*t.lo) << ", " << fmt(*t.hi) << "]";
  if (to_hours) o << "  = " << fmt(to_hours(*t.value)) << ' ' << hu;
  o << "\n";
}

// A deviation's unit by its key, an accelerometer's (its output in g; phase data in g*s gives the
// same): TDEV and TTOT are time deviations, tau x MDEV / sqrt 3, in g*s, the rest in g.
const char* unit_of(std::string_view key) { return key == "tdev" || key == "ttot" ? "g*s" : "g"; }

// Where a table's unit is not the values' own (TDEV, TTOT), its header says it.
std::string unit_in_header(std::string_view key) {
  return std::string_view(unit_of(key)) == "g" ? std::string() : std::string("; in ") + unit_of(key);
}

// A deviation's table: with its noise type and bounds, or "-" where it has none.
void print_deviation(std::ostream& o, an::Deviation type, const std::vector<an::DevPoint>& pts, bool bounded,
                     double confidence) {
  const std::string in = unit_in_header(an::to_string(type));
  o << an::to_string(type) << (bounded ? " (bounds " + confidence_shown(confidence) + in + "):\n" : " (no bounds" + in + "):\n");
  o << "         m        tau_s     n_terms alpha         lo          dev           hi\n";
  for (const auto& p : pts) {
    char line[160];
    if (bounded)
      std::snprintf(line, sizeof line, "%10zu %12.5g %11zu %5d %12.4e %12.4e %12.4e\n", p.m, p.tau_s, p.n_terms, p.alpha,
                    p.lo, p.dev, p.hi);
    else
      std::snprintf(line, sizeof line, "%10zu %12.5g %11zu %5s %12s %12.4e %12s\n", p.m, p.tau_s, p.n_terms, "-", "-",
                    p.dev, "-");
    o << line;
  }
  // Where the bounds' EDF takes another noise type than the one identified (the guard at few
  // averages, docs/analysis.md "EDF guard at long tau"), said under the table: the alpha column
  // alone read as the bounds' noise type (a metrologist's review).
  std::string guarded;
  for (const auto& p : pts)
    if (bounded && p.edf_alpha != p.alpha)
      guarded += (guarded.empty() ? "" : ", ") + std::to_string(p.m) + " (identified " + std::to_string(p.alpha) +
                 ", bounds " + std::to_string(p.edf_alpha) + ")";
  if (!guarded.empty())
    o << "  note: the bounds' EDF takes another alpha than the one identified at m = " << guarded
      << ": the EDF guard at few averages (JSON edf_alpha; docs/analysis.md)\n";
}

// A long-tau statistic's table. typed_noise: its alpha is shown, also without bounds (MTOT,
// TTOT and HTOT's bias removal's noise type). The stride is explained where one exceeds 1.
void print_long_tau(std::ostream& o, an::LongTau type, const std::vector<an::LongTauPoint>& pts, bool bounded,
                    bool typed_noise, double confidence) {
  o << an::to_string(type) << (bounded ? " (bounds " + confidence_shown(confidence) : std::string(" (no bounds"));
  o << unit_in_header(an::to_string(type));
  if (!bounded && typed_noise) o << "; alpha: the noise type of the bias removal";
  if (std::any_of(pts.begin(), pts.end(), [](const an::LongTauPoint& p) { return p.stride > 1; }))
    o << "; stride > 1: every stride-th start summed";
  o << "):\n";
  o << "         m        tau_s     n_terms alpha         lo          dev           hi      edf stride estimator\n";
  for (const auto& p : pts) {
    char alpha[8] = "-", lo[16] = "-", hi[16] = "-", edf[16] = "-";
    if (typed_noise) std::snprintf(alpha, sizeof alpha, "%d", p.alpha);
    if (bounded && p.bounds_note.empty()) {  // else "-": no interval at this EDF (noted below)
      std::snprintf(lo, sizeof lo, "%.4e", p.lo);
      std::snprintf(hi, sizeof hi, "%.4e", p.hi);
      std::snprintf(edf, sizeof edf, "%.1f", p.edf);
    }
    char line[200];
    std::snprintf(line, sizeof line, "%10zu %12.5g %11zu %5s %12s %12.4e %12s %8s %6zu %s\n", p.m, p.tau_s, p.n_terms,
                  alpha, lo, p.dev, hi, edf, p.stride, p.estimator.c_str());
    o << line;
  }
  for (const auto& p : pts)
    if (bounded && !p.bounds_note.empty()) o << "  m " << p.m << ": no bounds: " << p.bounds_note << "\n";
}

// A long-tau statistic in the JSON: bounds as the run has them; MTOT, TTOT and HTOT's alpha (the
// noise type of their bias removal) also without bounds, unless there is no noise (typed_noise).
json long_tau_json(const std::vector<an::LongTauPoint>& pts, an::LongTau type, bool bounded, bool typed_noise) {
  json a = analysis::long_tau_to_json(pts, bounded);
  if (!bounded && typed_noise && has_noise_bias(type))
    for (std::size_t i = 0; i < pts.size(); ++i) a[i]["alpha"] = pts[i].alpha;
  return a;
}

// RIG_ANALYZE_TIMING=1 prints each stage's wall and CPU time (all threads) to stderr: where the
// whole process spends its time (docs/analysis.md, "Speed"); CPU time stays meaningful on a
// loaded machine. Off by default: one getenv, no clock reads.
class StageTimer {
 public:
  StageTimer() : on_(std::getenv("RIG_ANALYZE_TIMING") != nullptr) {
    if (on_) wall_ = std::chrono::steady_clock::now(), cpu_ = std::clock();
  }
  void mark(const char* stage) {
    if (!on_) return;
    const auto wall = std::chrono::steady_clock::now();
    const std::clock_t cpu = std::clock();
    std::fprintf(stderr, "rig analyze: %-12s wall %8.2f ms  cpu %8.2f ms\n", stage,
                 std::chrono::duration<double, std::milli>(wall - wall_).count(),
                 1e3 * static_cast<double>(cpu - cpu_) / CLOCKS_PER_SEC);
    wall_ = wall, cpu_ = cpu;
  }

 private:
  bool on_;
  std::chrono::steady_clock::time_point wall_;
  std::clock_t cpu_ = 0;
};

// What --gaps does with a capture whose sample sequence breaks (CaptureGap): the deviations
// assume evenly spaced samples, so values joined across a gap are a (usually small) error the
// user must know of. join: keep every value and say so; longest: keep the longest gap-free
// stretch (values becomes it, from = its first sample); stop: a configuration error. Returns the
// note for the console and the JSON ("" without gaps).
std::string apply_gap_policy(const std::string& file, const std::string& policy, const std::vector<CaptureGap>& gaps,
                             std::vector<double>& values, std::size_t& from) {
  if (gaps.empty()) return "";
  std::uint64_t lost = 0;
  for (const CaptureGap& g : gaps) lost += g.lost;
  const CaptureGap& g0 = gaps.front();
  const std::string what = std::to_string(gaps.size()) + " gap(s) in the sample sequence, " + std::to_string(lost) +
                           " sample(s) lost; the first before sample " + std::to_string(g0.at) + " (seq " +
                           std::to_string(g0.seq_before) + " -> " + std::to_string(g0.seq_after) + ")";
  if (policy == "stop")
    throw InputError(file + ": " + what + "; --gaps join analyses across them, --gaps longest the longest gap-free stretch");
  if (policy == "longest") {
    std::size_t best_from = 0, best_len = gaps.front().at, start = 0;
    for (std::size_t k = 0; k <= gaps.size(); ++k) {
      const std::size_t end = k < gaps.size() ? gaps[k].at : values.size();
      if (end - start > best_len) best_from = start, best_len = end - start;
      start = end;
    }
    from = best_from;
    values = std::vector<double>(values.begin() + static_cast<std::ptrdiff_t>(best_from),
                                 values.begin() + static_cast<std::ptrdiff_t>(best_from + best_len));
    return what + "; --gaps longest: samples " + std::to_string(best_from) + ".." +
           std::to_string(best_from + best_len - 1) + " analysed, the longest of " + std::to_string(gaps.size() + 1) +
           " gap-free stretches";
  }
  return what + "; joined: the statistics treat the values as contiguous (--gaps longest analyses the longest "
                "gap-free stretch, --gaps stop refuses)";
}

constexpr double kMaxConfidence = 0.999999999;
// The numeric options' ranges, each refused (exit 2) with the value as typed.
void check_numeric_options(const Args& a) {
  if (!(a.overlap >= 0 && a.overlap <= 0.95))
    throw ConfigError("rig analyze: --overlap " + shortest_text(a.overlap) + ": the PSD segment overlap must be in [0, 0.95]");
  // At most 1 - 1e-9 (6.1 sigma): nearer 1 the chi-square quantiles of the long-tau statistics
  // overflow (0.9999999999999999 ended with exit 4 and Boost's words, a review).
  if (!(a.confidence > 0 && a.confidence <= kMaxConfidence))
    throw ConfigError("rig analyze: --confidence " + shortest_text(a.confidence) + ": must be in (0, " +
                      shortest_text(kMaxConfidence) + "]");
  if (a.rate && !(std::isfinite(*a.rate) && *a.rate >= capture::kMinRateHz && *a.rate <= capture::kMaxRateHz))
    throw ConfigError("rig analyze: --rate " + (a.rate_text.empty() ? shortest_text(*a.rate) : a.rate_text) +
                      ": the sample rate must be in [" + shortest_text(capture::kMinRateHz) + ", " +
                      shortest_text(capture::kMaxRateHz) + "] Hz");
  // 0 was taken silently (the automatic segment; the engine's smallest ring): a typed 0 is a slip.
  constexpr std::size_t kMinSegment = 8;  // welch()'s smallest (analysis/psd.cpp)
  if (a.segment && *a.segment < kMinSegment)
    throw ConfigError("rig analyze: --segment " + std::to_string(*a.segment) + ": a PSD segment has at least " +
                      std::to_string(kMinSegment) + " values (without --segment its length is chosen)");
  constexpr std::size_t kMaxMemoryMib = std::size_t{1} << 20;  // 1 TiB: MiB << 20 stays in a size_t
  if (a.memory_mib < 1 || a.memory_mib > kMaxMemoryMib)
    throw ConfigError("rig analyze: --memory-mib " + std::to_string(a.memory_mib) + ": the memory budget must be in 1.." +
                      std::to_string(kMaxMemoryMib) + " MiB");
}

// The files --svg DIR writes.
const char* const kSvgFiles[] = {"allan.svg", "psd.svg"};

// --svg DIR: an existing folder that takes files, or one folder to be made in an existing one
// (not a whole path: a mistyped path is not made into folders). Its plots may not be the input.
void check_svg_folder(const std::string& dir, const std::string& input, const std::string& input_name) {
  namespace fs = std::filesystem;
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0) {
    fs::path p(dir);
    if (!p.has_filename()) p = p.parent_path();  // "plots/"
    const fs::path parent = p.has_parent_path() ? p.parent_path() : fs::path(".");
    std::error_code ec;
    if (!fs::is_directory(parent, ec))
      throw ConfigError("rig analyze: --svg " + dir + ": the folder " + parent.string() +
                        " does not exist (--svg makes the plots' folder, not the path to it)");
    if (::access(parent.c_str(), W_OK | X_OK) != 0)
      throw ConfigError("rig analyze: --svg " + dir + ": cannot create a folder in " + parent.string());
    return;
  }
  if (!S_ISDIR(st.st_mode))
    throw ConfigError("rig analyze: --svg " + dir + ": not a folder (allan.svg and psd.svg are written into it)");
  if (::access(dir.c_str(), W_OK | X_OK) != 0) throw ConfigError("rig analyze: --svg " + dir + ": cannot create files in it");
  for (const char* name : kSvgFiles) {
    const std::string file = (fs::path(dir) / name).string();
    if (same_regular_file(file, input))
      throw ConfigError("rig analyze: --svg " + dir + ": " + file + " is the input file " + input_name +
                        " (it would be overwritten); give another folder");
    check_output_file(file, "rig analyze: --svg " + dir + ":");
  }
}

// Every output, before the input is read (a review: an unwritable --json was found after the
// whole analysis, with the summary printed and --json written beside a bad --svg; --json naming
// the input overwrote the record). Exit 2 naming the path.
void check_outputs(const Args& a) {
  namespace fs = std::filesystem;
  const std::string input_name = a.file == "-" ? "that standard input reads" : a.file;
  if (!a.json_out.empty()) {
    if (same_regular_file(a.json_out, a.file))
      throw ConfigError("rig analyze: --json " + a.json_out + ": is the input file " + input_name +
                        " (it would be overwritten); give another name");
    check_output_file(a.json_out, "rig analyze: --json");
  }
  if (a.svg_dir.empty()) return;
  check_svg_folder(a.svg_dir, a.file, input_name);
  if (a.json_out.empty()) return;
  std::error_code ec;
  const fs::path json_path = fs::weakly_canonical(a.json_out, ec);
  for (const char* name : kSvgFiles)
    if (!ec && json_path == fs::weakly_canonical(fs::path(a.svg_dir) / name, ec))
      throw ConfigError("rig analyze: --json " + a.json_out + ": is --svg " + a.svg_dir + "'s " + name +
                        "; give another name");
}

int run(const Args& a) {
  StageTimer timer;
  check_numeric_options(a);
  an::DevOptions base;
  // Each option's parse error names the option and its value (and, for --dev, the statistics
  // it also takes).
  auto parsed = [](const char* option, const std::string& value, auto parse, const char* hint = "") {
    try {
      return parse();
    } catch (const std::invalid_argument& e) {
      throw ConfigError(std::string("rig analyze: ") + option + " '" + value + "': " + e.what() + hint);
    }
  };
  base.data = parsed("--data", a.data, [&] { return an::parse_data_kind(a.data); });
  // --taus m:LIST: these averaging factors, for every deviation asked for, up to the last with a
  // complete term (past the grids' Stable32 caps: NIST SP 1065 publishes ADEV and HDEV at AF 2
  // of NBS14's 10 points, where the grid stops at 1); otherwise a grid.
  std::vector<std::size_t> listed;
  if (a.taus.rfind("m:", 0) == 0) {
    const std::string items = a.taus.substr(2);
    std::stringstream list(items + ",");  // a trailing ',' is an empty item too
    // At most 12 digits' worth, as before: no record this program reads has a term there.
    constexpr std::uint64_t largest_factor = 999'999'999'999;
    for (std::string m; std::getline(list, m, ',');) {
      const auto factor = whole_number(m, 1, largest_factor);
      if (!factor)
        throw ConfigError("rig analyze: --taus '" + a.taus + "': '" + m + "' is not an averaging factor (m:1,2,5: decimal whole numbers in [1, " +
                          std::to_string(largest_factor) + "], no leading zero)");
      listed.push_back(static_cast<std::size_t>(*factor));
    }
    if (listed.empty()) throw ConfigError("rig analyze: --taus '" + a.taus + "': no averaging factor (m:1,2,5)");
    std::sort(listed.begin(), listed.end());
    listed.erase(std::unique(listed.begin(), listed.end()), listed.end());
  } else {
    base.taus = parsed("--taus", a.taus, [&] { return an::parse_tau_grid(a.taus); }, " (or m:LIST, averaging factors: m:1,2,5)");
  }
  (void)parsed("--window", a.window, [&] { return an::parse_window(a.window); });
  // --dev: a comma-separated list of one Allan-family deviation and/or long-tau statistics.
  std::optional<an::Deviation> extra_dev;
  std::vector<an::LongTau> long_taus;
  std::stringstream names(a.dev);
  for (std::string name; std::getline(names, name, ',');) {
    if (const auto lt = an::parse_long_tau(name)) {
      if (std::find(long_taus.begin(), long_taus.end(), *lt) == long_taus.end()) long_taus.push_back(*lt);
      continue;
    }
    const an::Deviation d = parsed("--dev", a.dev, [&] { return an::parse_deviation(name); },  // names the choices
                                   " (or theo1|theoh|mtot|ttot|htot)");
    if (extra_dev && *extra_dev != d)
      throw ConfigError("rig analyze: --dev '" + a.dev + "': one Allan-family deviation, got two (" +
                        an::to_string(*extra_dev) + " and " + an::to_string(d) + "); theo1|theoh|mtot|ttot|htot may be added");
    extra_dev = d;
  }
  base.type = extra_dev.value_or(an::Deviation::OADEV);
  if (!listed.empty() && !long_taus.empty())
    throw ConfigError("rig analyze: --taus '" + a.taus + "': an explicit factor list is for the Allan family; the "
                      "long-tau statistics (--dev theo1|theoh|mtot|ttot|htot) take a grid (octave|decade|all|log:N)");
  const std::string channel = a.channel.value_or("x");
  if (channel != "x" && channel != "y") throw ConfigError("rig analyze: --channel '" + channel + "': must be x or y");
  if (a.no_oadev && base.type == an::Deviation::OADEV)
    throw ConfigError("rig analyze: --no-oadev needs --dev with another deviation (mdev, tdev, hdev, ...)");
  if (a.no_oadev && !a.svg_dir.empty())
    throw ConfigError("rig analyze: --svg plots OADEV and its noise terms: not with --no-oadev");

  // Standard input ("-") is named "stdin" in messages, as its lines are ("stdin:12: ...").
  const std::string input_name = a.file == "-" ? "stdin" : a.file;
  for (const auto& [opt, out] : {std::pair{"--json", &a.json_out}, std::pair{"--svg", &a.svg_dir}})
    if (*out == "-")
      throw ConfigError(std::string("rig analyze: ") + opt + " -: give a file or folder (standard output carries the "
                        "summary)");
  std::string input = a.input;
  std::string chosen_by = "--input " + input;  // how the kind was chosen, for the messages
  if (input == "auto") {
    const auto ext = std::filesystem::path(a.file).extension().string();
    input = ext == ".f64" || ext == ".bin" ? "f64"
            : ext == ".f32"                 ? "f32"
                                            : (ext == ".rigcap" || ext == ".cap" ? "capture" : "text");
    chosen_by = ext.empty() ? std::string("no extension: text") : "its " + shown_ascii(ext) + " name";
  }
  // Source: text and captures are held in memory; float64 files are streamed.
  if (a.channel && input != "capture")
    throw ConfigError("rig analyze: --channel is for capture files (x or y); " + input_name + " is read as " + input);
  if (a.gaps && input != "capture")
    throw ConfigError("rig analyze: --gaps is for capture files (their sample counter shows gaps); " + input_name +
                      " is read as " + input);
  const std::string gap_policy = a.gaps.value_or("join");
  std::vector<double> mem;
  std::unique_ptr<an::ChunkSource> src;
  std::optional<CaptureData> cap;
  std::string gap_note;
  std::size_t analysed_from = 0;  // the first capture sample analysed (--gaps longest)
  constexpr double kDefaultRateHz = 1000;
  double rate = a.rate.value_or(kDefaultRateHz);
  check_input_path(a.file, input, chosen_by);
  check_outputs(a);  // before anything is read: a bad output leaves nothing written
  std::size_t blank_lines = 0;  // noted below
  if (input == "text") {
    mem = read_text(a.file, &blank_lines);
  } else if (input == "f64") {
    // A file that fits the memory budget is mapped and analysed in place (one ring holds it all),
    // its values checked by the deviations' pass (which runs first, below) as it integrates them.
    src = std::make_unique<F64File>(a.file, (a.memory_mib << 20) / 2, /*check_in_pass=*/true);
  } else if (input == "f32") {
    mem = read_f32(a.file);
  } else if (input == "capture") {
    cap = read_capture(a.file, channel);
    mem = std::move(cap->values);
    if (!a.rate) rate = cap->header.rate_hz;
    gap_note = apply_gap_policy(a.file, gap_policy, cap->gaps, mem, analysed_from);
  } else {
    throw ConfigError("rig analyze: --input must be text, f64, f32 or capture, got '" + input + "'");
  }
  if (!src) src = std::make_unique<an::SpanSource>(mem);
  timer.mark("read");
  const std::uint64_t n = src->size();
  if (n < 3) throw InputError(input_name + ": " + std::to_string(n) + (n == 1 ? " value" : " values") + "; at least 3 are needed");
  // Short records (NBS14's 9/10-point sets) are analysed; what is not meaningful on them is said.
  std::vector<std::string> notes;
  if (blank_lines)
    notes.push_back(std::to_string(blank_lines) + " blank line" + (blank_lines > 1 ? "s" : "") + " between values "
                    "skipped: the values around " + (blank_lines > 1 ? "them" : "it") + " are joined, not read as "
                    "missing samples");
  if (!gap_note.empty()) notes.push_back(gap_note);
  if (!a.rate && !cap)  // every tau and noise term scales with it (a review: a 1 s file read at 1 kHz, silently)
    notes.push_back("no --rate: " + shortest_text(kDefaultRateHz) + " Hz assumed (every tau and noise term scales with it)");
  // A capture's header says its rate; another --rate is the user's to give (a recording whose
  // header was written wrong), but never silently (a review: every tau and term scaled by 2).
  if (cap && a.rate && *a.rate != cap->header.rate_hz)
    notes.push_back("--rate " + shortest_text(*a.rate) + " Hz overrides the capture header's " +
                    shortest_text(cap->header.rate_hz) + " Hz: every tau and noise term is computed at --rate's");
  if (cap && cap->lost_at_start)
    notes.push_back("samples were lost before the first one read (the capture's first block is damaged: the reader's "
                    "notes name it); the record starts after them, nothing is joined");
  std::optional<std::size_t> few_values_note;  // dropped for a constant record, which has neither (below)
  if (n < 30)
    few_values_note = notes.size(), notes.push_back(std::to_string(n) + " values: every tau has fewer than 30 averages (B1 noise identification); "
                    "the bounds rest on a few degrees of freedom and the noise terms on a few points (which terms "
                    "are reported can change with the values' last digits: a review found 4 ulps flip it)");
  // Sizes are checked where they are needed, before the long work: the deviation needs 3 phase
  // points (deviations_stream says so), the PSD one whole segment. A record shorter than the
  // default segment gets no PSD and a note (the deviations are still meaningful); a --segment
  // the record cannot fill is the caller's error.
  an::WelchOptions wo;
  wo.window = an::parse_window(a.window);
  wo.segment = a.segment.value_or(0);  // 0: welch_segment chooses
  wo.overlap = a.overlap;
  wo.threads = a.threads;
  bool want_psd = base.data == an::DataKind::Frequency && !a.no_psd;
  if (base.data == an::DataKind::Phase && !a.no_psd)  // said, not silently left out (a review)
    notes.push_back("no PSD: phase data (the PSD is of the rate, frequency data: give --data freq for it)");
  if (a.no_bounds)
    // The noise terms' fit weighs each point by the model's own EDF, never by the point's
    // identified noise (docs/analysis.md, "Noise terms" (b)): it said "weighted alike", wrongly (a review).
    notes.push_back("--no-bounds: no noise identification and no bounds on the deviations (alpha, edf, lo and hi are "
                    "null); the noise terms and their bounds are the same as with bounds (their fit weighs each point "
                    "by the model's own EDF, not by the points' identified noise)");
  // MTOT, TTOT and HTOT divide by their noise type's bias (theo.hpp tot_bias): --no-bounds once
  // took white FM for it and changed their values (HTOT by 12 % on a random walk, a review).
  // Their noise is identified on OADEV as with bounds, and their alpha says the type used.
  const bool bias_types = std::any_of(long_taus.begin(), long_taus.end(), has_noise_bias);
  const bool identify_oadev = !a.no_bounds || (bias_types && !a.no_oadev);
  if (a.no_bounds && bias_types)
    notes.push_back("--no-bounds with mtot, ttot, htot: the noise is still identified for their bias removal (on OADEV, "
                    "as with bounds, so their values do not depend on --no-bounds); their alpha is the type it used");
  if (want_psd && n < an::welch_segment(n, wo)) {
    if (a.segment.has_value())
      throw ConfigError(input_name + ": " + std::to_string(n) + " values are fewer than one PSD segment of " +
                        std::to_string(an::welch_segment(n, wo)) + " (give a shorter --segment, or --no-psd)");
    notes.push_back("no PSD: " + std::to_string(n) + " values are fewer than one Welch segment of " +
                    std::to_string(an::welch_segment(n, wo)) + " (give --segment to have one)");
    want_psd = false;
  }

  // One pass for OADEV (noise terms, the contract's "oadev") and the requested deviation; with
  // --no-oadev only the requested one (a user who wants MDEV alone does not wait for OADEV).
  std::vector<an::DevOptions> opts;
  base.rate_hz = rate;
  base.confidence = a.confidence;
  base.bounds = !a.no_bounds;
  base.threads = a.threads;
  an::DevOptions oadev = base;
  oadev.type = an::Deviation::OADEV;
  oadev.bounds = identify_oadev;
  if (!a.no_oadev) opts.push_back(oadev);
  if (base.type != an::Deviation::OADEV) opts.push_back(base);
  if (!listed.empty()) {  // each deviation takes the listed factors it has a term at; the others are named
    const std::uint64_t n_phase = base.data == an::DataKind::Frequency ? n + 1 : n;
    for (an::DevOptions& o : opts) {
      std::string dropped;
      for (std::size_t m : listed)
        if (an::factor_in_range(o.type, n_phase, m)) o.factors.push_back(m);
        else dropped += (dropped.empty() ? "" : ", ") + std::to_string(m);
      if (o.factors.empty())
        throw ConfigError(input_name + ": --taus " + a.taus + ": no factor with a complete term of " +
                          an::to_string(o.type) + " on " + std::to_string(n_phase) + " phase points");
      if (!dropped.empty())
        notes.push_back(std::string(an::to_string(o.type)) + ": factor(s) " + dropped + " of --taus " + a.taus +
                        " left out (no complete term on " + std::to_string(n_phase) + " phase points)");
    }
  }
  // --taus all asks for every factor up to T/4 (T/2 for TOTDEV), each a sum over the record:
  // refused beyond kAllTermSums (allan.hpp), naming the grids that cover the same taus.
  if (listed.empty() && base.taus.kind == an::TauGrid::All && !a.no_work_limit) {
    using an::kAllTermSums;
    const std::uint64_t n_phase = base.data == an::DataKind::Frequency ? n + 1 : n;
    // Every statistic's factor count (the long-tau ones at n/2, a floor) times the record.
    double factors = static_cast<double>(long_taus.size()) * static_cast<double>(n_phase) / 2;
    for (const an::DevOptions& o : opts) factors += static_cast<double>(an::max_factor(o.type, n_phase));
    const double work = factors * static_cast<double>(n_phase);  // term sums
    const double per_value = factors / static_cast<double>(std::max<std::uint64_t>(n_phase, 1));  // work / n^2
    if (work > kAllTermSums) {
      char sums[32], most[32];
      std::snprintf(sums, sizeof sums, "%.2g", work);
      std::snprintf(most, sizeof most, "%.0f", std::floor(std::sqrt(kAllTermSums / per_value)));
      throw ConfigError(input_name + ": --taus all on " + std::to_string(n) + " values asks for every averaging factor (" +
                        sums + " term sums): give --taus log:N (log:100 is the default, log:100000 the finest) or "
                        "m:LIST, or --taus all on at most " + most + " values (--no-work-limit runs it regardless)");
    }
  }
  an::StreamOptions so;
  so.memory_budget_bytes = a.memory_mib << 20;
  an::Drift drift;  // R is read from it (noise_terms.hpp); the pass keeps its sums
  so.drift = &drift;
  double phase_abs_max = 0;  // the phase's largest magnitude: its rounding floor (below)
  so.phase_abs_max = &phase_abs_max;
  // A record too short for any tau of the grid (the grids stop at T/4, Stable32's rule: 3..8
  // values have none) is still analysed at tau0 (m = 1, which every deviation's estimator
  // allows from 3 values on), with a note.
  std::vector<std::vector<an::DevPoint>> devs;
  const auto compute = [&] {
    try {
      devs = an::deviations_stream(*src, opts, so);
    } catch (const std::invalid_argument& e) {
      throw InputError(input_name + ": " + e.what());
    }
  };
  compute();
  if (std::any_of(devs.begin(), devs.end(), [](const auto& d) { return d.empty(); })) {
    notes.push_back("the tau grid " + a.taus + " has no tau within T/4 of " + std::to_string(n) +
                    " values: tau0 only (m = 1)");
    for (an::DevOptions& o : opts) o.factors = {1};
    compute();
  }
  for (std::size_t k = 0; k < devs.size(); ++k)
    if (devs[k].empty())
      throw InputError(input_name + ": " + std::to_string(n) + " values are too few for any tau of " +
                       an::to_string(opts[k].type) + " (" + a.taus + ")");
  // The record's span: n frequency values cover n tau0; n phase points, n - 1 (a review: ten
  // phase points were said to be 10 s at 1 Hz).
  const double record_s = static_cast<double>(base.data == an::DataKind::Phase ? n - 1 : n) / rate;
  // OADEV identified for the total family's bias alone (--no-bounds): kept for it, and reported
  // and fitted as --no-bounds has it.
  std::vector<an::DevPoint> oadev_identified;
  if (a.no_bounds && identify_oadev) {
    oadev_identified = devs[0];
    devs[0] = without_identification(std::move(devs[0]));
  }
  // A constant record or a straight phase line: its deviations are rounding, not noise. Nothing
  // is identified or bounded (null, as --no-bounds), the noise terms say why they are null, and
  // there is no PSD (its "peaks" were rounding noise at 1e-60, a review).
  const bool constant = no_noise_above_rounding(devs, end_value_scale(*src), base.data);
  // The mirror of the readers' 2^333 limit: a record whose values all lie nearer 0 than 2^-333.
  // From 1e-154 on their squared differences leave a double's normal range, so the deviations lose
  // their digits or read 0 (a review: values of 1e-310 and 1e-200 were 'the record is constant').
  // No unit the rig records comes near it. "All": the values sampled over the record are, and the
  // first statistic (OADEV unless --no-oadev) allows it: in the values' units (dev, or dev * tau
  // for phase) OADEV is at most 2 sqrt 2 times the largest value (a second difference of four
  // values, over sqrt 2), so the limit there is 3 * 2^-333 (at 2^-333 a record of values just
  // below it was analysed, a review).
  {
    double dev_max = 0;
    for (const auto& p : devs.front()) dev_max = std::max(dev_max, base.data == an::DataKind::Phase ? p.dev * p.tau_s : p.dev);
    if (const double mag = dev_max < 3 / an::kMaxMagnitude ? sampled_magnitude(*src) : 0.0;
        mag > 0 && mag < 1 / an::kMaxMagnitude) {
      char shown[32];
      std::snprintf(shown, sizeof shown, "%.3g", mag);
      throw InputError(input_name + ": its values (up to " + shown +
                       " in magnitude) are nearer 0 than 2^-333 = 5.7e-101, the mirror of the 2^333 limit (from "
                       "1e-154 on their squared differences leave a double's normal range, the deviations lose "
                       "their digits and then read 0; not a measurement in any unit: scale the record)");
    }
  }
  const std::string constant_what = base.data == an::DataKind::Phase
                                        ? "the phase is a straight line (a constant frequency)"
                                        : "the record is constant";
  if (constant) {
    // Its bounds and noise terms are none, not few (a review: "the bounds rest on a few degrees of
    // freedom and the noise terms on a few points", then "no bounds and no noise terms").
    if (few_values_note) notes.erase(notes.begin() + static_cast<std::ptrdiff_t>(*few_values_note));
    notes.push_back(constant_what + ": every deviation is 0 or the rounding of the values, so there is no noise to "
                    "identify, no bounds and no noise terms");
    if (want_psd) notes.push_back("no PSD: the record is constant (its spectrum would be the rounding of the values)");
    want_psd = false;
  }
  const bool bounded = !a.no_bounds && !constant;
  // A deviation that is 0 or the rounding of the values where OADEV is not: HDEV and OHDEV remove a
  // linear frequency drift, so an exact ramp's are 0. No noise type and no bounds there, said (an
  // analysis review: HDEV 0 with alpha -2 and bounds [0, 0]).
  std::vector<bool> dev_bounded(devs.size(), bounded);
  // The phase's rounding floor per point (0.5 ulp of its largest value over m, in the deviation's
  // own units before TDEV's tau scaling; docs/analysis.md): a ramp whose values are not exact
  // (1 + k 1e-6) left HDEV at that floor, 41 ulps of the values, with noise types (a re-test).
  const double phase_ulp =
      phase_abs_max > 0 ? std::nextafter(phase_abs_max, std::numeric_limits<double>::infinity()) - phase_abs_max : 0;
  const auto phase_floor = [&](const an::DevPoint& pt) { return 0.5 * phase_ulp / static_cast<double>(pt.m); };
  const auto unscaled = [&](std::size_t k, const an::DevPoint& pt) {
    return opts[k].type == an::Deviation::TDEV ? pt.dev * std::sqrt(3.0) / pt.tau_s : pt.dev;
  };
  const auto at_phase_floor = [&](std::size_t k) {
    return !devs[k].empty() && std::all_of(devs[k].begin(), devs[k].end(), [&](const an::DevPoint& pt) {
      return unscaled(k, pt) <= 2 * phase_floor(pt);
    });
  };
  if (bounded) {
    const double scale = end_value_scale(*src);
    for (std::size_t k = 0; k < devs.size(); ++k)
      if (no_noise_above_rounding({devs[k]}, scale, base.data) || at_phase_floor(k)) {
        dev_bounded[k] = false;
        devs[k] = without_identification(std::move(devs[k]));
        notes.push_back(std::string(an::to_string(opts[k].type)) + ": every point is 0 or the rounding of the values or of their "
                        "phase (it removes a linear frequency drift, and there is no noise beside it): no noise type "
                        "and no bounds");
      }
  }
  // The phase's own rounding: every difference of P carries units in the last place of its largest
  // value, and a frequency drift grows P as the square of time, so a Hadamard deviation (which
  // removes the drift) can sink to that floor (an analysis review: HDEV of a 1e5-value ramp with
  // noise 1e-6 off by 3.6 % at m = 1, with 0.3 % bounds). P is a running sum, so its rounding
  // accumulates along the record like a random walk: a difference over m steps carries about m
  // roundings, and the variance it adds grows as m ulp^2 / m^2, not ulp^2 / m^2 (a review: with
  // 0.5 ulp / m the note said 1.6e-6 where the error was 3.6e-6 at m = 1, 1.3e-6 at m = 100 where
  // it said 1.5e-8). Measured against exact integer references on 1e5- and 2e5-value ramps, the
  // error stays below 0.7 times m (2 ulp(max |P|) / m)^2 / 2 over m = 1..1000; that is taken, and
  // a relative error of the deviation above 1e-8 is said (no realistic record comes near).
  if (!constant && phase_abs_max > 0) {
    for (std::size_t k = 0; k < devs.size(); ++k) {
      if (bounded && !dev_bounded[k]) continue;  // already said to be rounding
      std::size_t count = 0, m_worst = 0;
      double worst = 0;
      for (const an::DevPoint& pt : devs[k]) {
        const double dev = unscaled(k, pt);
        if (!(dev > 0)) continue;
        const double floor = 4 * phase_floor(pt), rel = 0.5 * static_cast<double>(pt.m) * (floor / dev) * (floor / dev);
        if (rel > 1e-8) {
          ++count;
          if (rel > worst) worst = rel, m_worst = pt.m;
        }
      }
      if (count)
        notes.push_back(fmt::format("{}: at {} tau{} the phase's rounding may move the deviation by more than 1e-8 of "
                                    "its value (up to about {:.1e}, at m = {}): the integrated record reaches {:.3g} (a "
                                    "frequency drift grows it as the square of time), so fewer digits are significant "
                                    "there; the record with its drift removed reads them better",
                                    an::to_string(opts[k].type), count, count > 1 ? "s" : "", worst, m_worst,
                                    phase_abs_max / (base.data == an::DataKind::Phase ? rate : 1.0)));
    }
  }
  // A chi-square's median is below its mean, so at a low --confidence and few degrees of freedom the
  // interval lies wholly above the estimate (Stable32's and SP 1065's interval, kept for parity):
  // said, not left for a reader to take for an error (an analysis review: lo > dev, no note).
  for (std::size_t k = 0; k < devs.size(); ++k) {
    if (!dev_bounded[k]) continue;
    std::size_t above = 0;
    double edf_max = 0;
    for (const an::DevPoint& pt : devs[k])
      if (pt.lo > pt.dev) ++above, edf_max = std::max(edf_max, pt.edf);
    if (above)
      notes.push_back(fmt::format("{}: at {} tau{} (EDF up to {:.3g}) the {} interval lies wholly above the deviation: "
                                  "a chi-square's median is below its mean, so a low confidence's interval on few "
                                  "degrees of freedom need not hold the estimate (the interval is SP 1065's, as Stable32's)",
                                  an::to_string(opts[k].type), above, above > 1 ? "s" : "", edf_max,
                                  confidence_shown(a.confidence)));
  }
  // The file is read again only by the PSD and the long-tau statistics. Without them its mapping
  // (one page-table entry per 4 KiB: 7000 for 3.6e6 values, about 0.5 ms to tear down) is
  // released on another thread, while this one fits the noise terms and writes the JSON, instead
  // of in the process's exit, which the user waits for. Joined when run() returns.
  std::jthread release_source;
  if (!want_psd && long_taus.empty()) release_source = std::jthread([s = std::move(src)]() mutable { s.reset(); });
  timer.mark("deviations");
  const std::vector<an::DevPoint>* oadev_pts = a.no_oadev ? nullptr : &devs[0];
  const std::vector<an::DevPoint>* extra_pts = base.type != an::Deviation::OADEV ? &devs.back() : nullptr;
  // The noise-term fit (serial: about 8 ms for log:100's 108 taus) runs on a thread of its own
  // while this one goes on to the long-tau statistics and the Welch PSD, which then share the two
  // cores with it; joined before the PSD's model fit (its band follows the fitted taus) and the
  // JSON take the terms. Without either there is nothing to overlap.
  std::optional<an::NoiseTerms> terms;  // read from OADEV
  std::exception_ptr fit_error;
  const auto fit_terms = [&] {
    try {
      terms = constant ? an::no_noise_terms(constant_what + ": every deviation is 0 or the rounding of the values, "
                                            "no noise to fit", a.confidence)
                       : an::noise_terms(*oadev_pts, record_s, an::kRMinRecordS, drift, a.confidence);
    } catch (...) {
      fit_error = std::current_exception();
    }
  };
  std::jthread fit;
  if (oadev_pts) {
    if (want_psd || !long_taus.empty()) fit = std::jthread(fit_terms);
    else fit_terms();
  }
  const auto join_fit = [&] {
    if (fit.joinable()) fit.join();
    if (fit_error) std::rethrow_exception(fit_error);
  };
  timer.mark("noise terms");

  // Long-tau statistics: on the record in memory (16 bytes per value with its phase), noise
  // types from the OADEV above (with its EDF guard).
  std::vector<std::vector<an::LongTauPoint>> longs;
  if (!long_taus.empty()) {
    std::vector<double> held;
    std::span<const double> values;
    if (const double* p = src->contiguous()) {
      values = std::span<const double>(p, n);
    } else {
      held.resize(n);
      if (src->read_at(0, held) != n) throw InputError(input_name + ": the file ended early");
      values = held;
    }
    for (an::LongTau t : long_taus) {
      an::LongTauOptions lo;
      lo.type = t;
      lo.data = base.data;
      lo.rate_hz = rate;
      lo.taus = base.taus;
      lo.confidence = a.confidence;
      lo.bounds = !a.no_bounds;
      lo.threads = a.threads;
      // Else long_tau computes an octave OADEV for the noise types.
      if (oadev_pts) lo.noise_ref = oadev_identified.empty() ? *oadev_pts : oadev_identified;
      try {
        longs.push_back(an::long_tau(values, lo));
      } catch (const std::invalid_argument& e) {
        throw InputError(input_name + ": " + e.what());
      }
    }
    timer.mark("long tau");
  }
  // MTOT's and TTOT's bounds at short tau are not a `confidence` interval: SP 1065's bias factor
  // and EDF are large-m values (white FM, an outside check: 0 % held at m = 1, 23.5 % at m = 4,
  // 54-56 % at m = 8..32, docs/analysis.md). Said where the record has such points (an
  // instrument engineer's review: only the docs said it).
  for (std::size_t k = 0; bounded && k < longs.size(); ++k) {
    if (long_taus[k] != an::LongTau::MTOT && long_taus[k] != an::LongTau::TTOT) continue;
    const auto short_m = std::count_if(longs[k].begin(), longs[k].end(), [](const an::LongTauPoint& p) { return p.m < 64; });
    if (short_m > 0)
      notes.push_back(fmt::format("{}: the bounds at its {} tau{} with m < 64 do not hold {:.3g} % (SP 1065's bias "
                                  "factor and EDF are large-m values: on white FM they held 0 % at m = 1, 24 % at m = 4, "
                                  "55 % at m = 8..32); read {}'s bounds there",
                                  an::to_string(long_taus[k]), short_m, short_m == 1 ? "" : "s", 100 * a.confidence,
                                  long_taus[k] == an::LongTau::MTOT ? "mdev" : "tdev"));
  }

  json j;
  j["n"] = n;
  j["rate_hz"] = rate;
  j["data"] = an::to_string(base.data);
  j["file"] = a.file;
  j["input"] = input;
  j["record_s"] = record_s;
  j["confidence"] = a.confidence;
  if (oadev_pts) j["oadev"] = analysis::dev_to_json(*oadev_pts, dev_bounded.front());
  if (extra_pts) j[an::to_string(base.type)] = analysis::dev_to_json(*extra_pts, dev_bounded.back());
  for (std::size_t k = 0; k < longs.size(); ++k)
    j[an::to_string(long_taus[k])] = long_tau_json(longs[k], long_taus[k], bounded, !constant);
  // Each deviation's unit (an analysis review: TDEV's g*s said nowhere).
  {
    json units = json::object();
    if (oadev_pts) units["oadev"] = unit_of("oadev");
    if (extra_pts) units[an::to_string(base.type)] = unit_of(an::to_string(base.type));
    for (const an::LongTau t : long_taus) units[an::to_string(t)] = unit_of(an::to_string(t));
    j["units"] = units;
  }
  if (cap) {
    j["capture"] = {{"serial", cap->header.serial}, {"phase", cap->header.phase},
                    {"orientation", cap->header.orientation}, {"channel", channel},
                    {"complete", cap->recovery.complete}, {"truncated", cap->recovery.truncated},
                    {"samples", cap->recovery.samples}, {"damaged_blocks", cap->recovery.damaged_blocks},
                    {"problem", cap->recovery.problem}, {"notes", cap->recovery.notes},
                    {"non_finite", cap->recovery.non_finite}, {"y_absent", cap->recovery.y_absent}};
    std::uint64_t lost = 0;
    for (const CaptureGap& g : cap->gaps) lost += g.lost;
    j["capture"]["gaps"] = cap->gaps.size();
    j["capture"]["lost"] = lost;
    j["capture"]["gap_policy"] = gap_policy;
    j["capture"]["lost_at_start"] = cap->lost_at_start;
    j["capture"]["analysed_from"] = analysed_from;
    j["capture"]["analysed_samples"] = n;
  }

  // PSD (frequency data only: for phase data it would be of the integral).
  std::optional<an::Psd> psd;
  std::vector<an::Peak> peaks;
  timer.mark("json build");
  if (want_psd) {
    try {
      psd = an::welch(*src, rate, wo);
    } catch (const std::invalid_argument& e) {
      throw InputError(input_name + ": " + e.what());
    }
    peaks = an::find_peaks(*psd, 10.0, 20);
    json pj = {{"method", "welch"}, {"window", a.window}, {"segment", psd->segment}, {"segments", psd->segments},
               {"enbw_hz", psd->enbw_hz}};
    pj["peaks_hz"] = json::array();
    pj["peaks"] = json::array();
    for (const auto& p : peaks) {
      pj["peaks_hz"].push_back(p.f_hz);
      pj["peaks"].push_back({{"f_hz", p.f_hz}, {"psd", p.psd}, {"prominence_db", p.prominence_db}});
    }
    const double h0 = an::white_level(*psd, 0.05 * rate, 0.45 * rate);
    pj["white_level"] = h0;  // unit^2/Hz, the median over 5..45 % of the rate (biased by Q)
    // N from the PSD model (Q, N, B, K; analysis/psd.hpp psd_noise_fit) over 4 bins above DC
    // (the window's leakage of the red terms) to 45 % of the rate, or to 1/(2 tau) of the
    // shortest tau the Allan model fitted where it left shorter ones out as not described by it
    // (tones, a band): the cross-check compares like with like. Over the whole band a review read
    // 5x the Allan N on the rig's own capture, without a word. The median's N without a fit.
    join_fit();
    const double bin = rate / static_cast<double>(psd->segment), f_lo = 4 * bin;
    double f_hi = 0.45 * rate;
    if (terms && terms->model.ok && terms->model.dropped_short > 0 && !terms->model.tau_s.empty())
      // A decade at least (and 8 bins): over less the model's N, B and K are near one shape, and a
      // 72 Hz line's record (the fit from 0.512 s: 0.24..0.98 Hz, 12 bins) read N anywhere from 0
      // to the truth by seed (an outside re-test).
      f_hi = std::min(f_hi, std::max({0.5 / terms->model.tau_s.front(), f_lo + 8 * bin, 10 * f_lo}));
    const an::PsdTerms pt = an::psd_noise_fit(*psd, f_lo, f_hi, peaks);
    const double n_psd = pt.ok ? pt.N : std::sqrt(h0 / 2);
    pj["n_from_psd"] = n_psd;  // unit*s^0.5
    pj["n_from_psd_per_hour"] = an::n_per_hour(n_psd);
    // The band the N above was read over: the model's, or the median's where the fit failed.
    pj["n_fit_band_hz"] = pt.ok ? json{f_lo, f_hi} : json{0.05 * rate, 0.45 * rate};
    // Said where it does not confirm the Allan N, or gives it no share (analysis/psd.hpp).
    if (terms) {
      const std::string note = an::psd_n_note(terms->N.value.value_or(0.0), n_psd, pt.ok, pt.ok ? f_lo : 0.05 * rate,
                                              pt.ok ? f_hi : 0.45 * rate);
      if (!note.empty()) notes.push_back(note);
    }
    // A line in the record: past a few of its periods its Allan variance falls as 1/tau^2, the
    // white-phase slope, as a Q of a / (2 pi f) would (a the line's RMS, from its PSD peak times
    // the bin's ENBW; docs/plant.md): on average 3 a^2 / (4 pi^2 f^2 tau^2) (sin^4 averages 3/8).
    // Said where that is a tenth or more of the Allan variance at the shortest tau the noise model
    // fitted, whichever terms it reported (an instrument engineer's review: a 72 Hz line in white
    // noise read Q 1.0e-7 and B 1.5e-7, neither injected, and N 34 % low, without a word; a
    // re-test: a note keyed to Q missed a B the line made).
    if (terms && terms->model.ok && !terms->model.tau_s.empty() && terms->model.avar.front() > 0)
      for (const auto& pk : peaks) {
        const double rms = std::sqrt(pk.psd * psd->enbw_hz), tau = terms->model.tau_s.front();
        const double w = 2 * std::numbers::pi * pk.f_hz * tau;
        const double share = 3 * rms * rms / (w * w) / terms->model.avar.front();
        if (!(share >= 0.1)) continue;
        char what[700];
        std::snprintf(what, sizeof what,
                      "psd: the line at %.4g Hz (RMS about %.3g) is about %.0f %% of the Allan variance at tau = %.3g "
                      "s, the shortest tau the noise model fitted: past a few of its periods a line falls as 1/tau^2, "
                      "as a Q of %.3g (a/(2 pi f)) would, so the Q, N and B read there may be partly that line's and not "
                      "the record's noise",
                      pk.f_hz, rms, 100 * std::min(share, 1.0), tau, rms / (2 * std::numbers::pi * pk.f_hz));
        notes.push_back(what);
        break;  // the strongest such line (peaks are strongest first)
      }
    // Only N is a cross-check; the other terms give the band's other slopes somewhere to go and
    // are not measurements (a review read K 13x above the Allan model's upper limit on white FM).
    pj["psd_fit"] = {{"ok", pt.ok}, {"bins", pt.bins}, {"bins_left_out_at_peaks", pt.left_out}, {"Q", pt.Q}, {"N", pt.N}, {"B", pt.B}, {"K", pt.K},
                     {"note", "N is the cross-check of the Allan N; Q, B and K are the fit's terms for the band's other "
                              "slopes, without bounds or a test that the data hold them: not measurements (the Allan "
                              "noise terms are)"}};
    j["psd"] = pj;
  }

  j["notes"] = notes;  // always there (an empty list): the docs list the key, and a reader need not test for it
  timer.mark("psd");
  join_fit();
  if (terms) j["noise_terms"] = analysis::noise_terms_to_json(*terms);
  // Every output is made before the first is written (their paths were checked at the start).
  std::vector<std::pair<std::filesystem::path, std::string>> outputs;  // --json's first
  if (!a.json_out.empty()) outputs.emplace_back(a.json_out, j.dump(2) + "\n");
  if (!a.svg_dir.empty()) {
    const std::string name = a.file == "-" ? input_name : std::filesystem::path(a.file).filename().string();
    // The report's plotter, fed the same JSON views as --json writes.
    outputs.emplace_back(std::filesystem::path(a.svg_dir) / kSvgFiles[0],
                         report::to_svg_file(report::allan_plot(j["oadev"], &j["noise_terms"], a.confidence, "allan",
                                                                "OADEV of " + name, "#1f77b4")));
    if (psd)
      outputs.emplace_back(std::filesystem::path(a.svg_dir) / kSvgFiles[1],
                           report::to_svg_file(report::psd_plot(analysis::psd_to_json(*psd, peaks), "psd",
                                                                "PSD of " + name, "#1f77b4", psd->rate_hz)));
    std::error_code ec;
    std::filesystem::create_directory(a.svg_dir, ec);  // one folder, in a folder checked to exist
    if (ec) throw ConfigError("rig analyze: --svg " + a.svg_dir + ": cannot create: " + ec.message());
  }
  for (const auto& [path, text] : outputs)
    write_output_file(path.string(), text, !a.json_out.empty() && path == a.json_out ? "rig analyze: --json" : "rig analyze: --svg");
  timer.mark("outputs");

  // Console summary.
  std::ostream& o = std::cout;
  if (cap) {  // what the capture reader recovered, damage included (docs/capture-format.md)
    o << cap->recovery.summary(a.file) << "\n";
    for (const auto& note : cap->recovery.notes) o << "  " << note << "\n";
    if (!cap->recovery.complete) std::cerr << "rig analyze: warning: " << cap->recovery.summary(a.file) << "\n";
    if (!cap->gaps.empty() && gap_policy == "join") std::cerr << "rig analyze: warning: " << input_name << ": " << gap_note << "\n";
  }
  // A raw file's kind is said (a review: a float32 file named .bin read as float64 without a word).
  const std::string raw = input == "f64" ? "raw float64" : input == "f32" ? "raw float32" : "";
  o << input_name << ": " << n << " values, " << shortest_text(rate) << " Hz, " << record_s << " s, data "
    << an::to_string(base.data) << (raw.empty() ? std::string() : "; read as " + raw + " (" + chosen_by + ")") << "\n";
  for (const auto& note : notes) o << "note: " << note << "\n";
  for (std::size_t k = 0; k < devs.size(); ++k) print_deviation(o, opts[k].type, devs[k], dev_bounded[k], a.confidence);
  for (std::size_t k = 0; k < longs.size(); ++k)
    print_long_tau(o, long_taus[k], longs[k], bounded, bounded || (has_noise_bias(long_taus[k]) && !constant),
                   a.confidence);
  if (terms) {
    o << "noise terms (tau in s; passport units after '='; bounds " << confidence_shown(a.confidence) << "):\n";
    print_term(o, "Q", terms->Q, an::q_per_hour, "g*h");
    print_term(o, "N", terms->N, an::n_per_hour, "g*h^0.5");
    print_term(o, "B", terms->B, nullptr, "");
    // How that B was read, and the model's beside it: the paper's method reads B off the curve
    // even where no flicker is in it (a metrologist's review read "B = 5.2e-05 g" on records with
    // none as a measured flicker floor; the model's B was null there).
    if (terms->B.value) {
      const std::string how = terms->b_method == "flat_segment"         ? "the paper's method, on the flat segment"
                              : terms->b_method == "polynomial_minimum" ? "the paper's method, at the polynomial's minimum "
                                                                          "(no flat segment: a bound from above)"
                                                                        : "the model's (least squares)";
      o << "      read by " << how;
      if (terms->b_method != "least_squares") {
        const an::Term& m = terms->wls.B;
        o << "; the model's B: ";
        if (m.value)
          o << fmt(*m.value) << ' ' << m.unit << (m.lo && m.hi ? "  [" + fmt(*m.lo) + ", " + fmt(*m.hi) + "]" : "");
        else
          o << "null" << (m.hi ? ", upper limit " + fmt(*m.hi) + " " + m.unit : std::string()) << " (no flicker in the model)";
      }
      o << "\n";
    }
    if (terms->tau_cp_s) o << "  tau_cp = " << *terms->tau_cp_s << " s\n";
    print_term(o, "K", terms->K, an::k_per_hour, "g/h^0.5");
    print_term(o, "R", terms->R, an::r_per_hour, "g/h");
  }
  if (psd) {
    // Each peak with its alias, as report.html and --svg label it (docs/analysis.md, "PSD peaks
    // and aliases"): the record cannot tell f from fs - f.
    o << "psd: welch " << a.window << ", segment " << psd->segment << " x " << psd->segments << "; peaks:";
    for (std::size_t i = 0; i < peaks.size(); ++i) o << (i ? ", " : " ") << report::peak_label(peaks[i].f_hz, psd->rate_hz);
    o << (peaks.empty() ? " none\n" : "\n");  // a bare "peaks:" read as cut off (a re-test)
    const json& pj = j["psd"];
    o << "  N from the PSD model (the cross-check of the Allan N) = " << fmt(pj["n_from_psd"].get<double>())
      << " over " << pj["n_fit_band_hz"][0].get<double>() << ".." << pj["n_fit_band_hz"][1].get<double>() << " Hz\n";
  }
  timer.mark("console");
  return kExitPass;
}

}  // namespace

void add_analyze(CLI::App& app, int& rc) {
  auto args = std::make_shared<Args>();
  auto* sub = app.add_subcommand("analyze", "Allan deviation with bounds, noise terms and PSD of a recording");
  sub->add_option("file", args->file, "recording (text: one value per line, '#' comments; f64: raw LE float64; f32: raw LE float32; "
                                      "capture: the rig's capture file; - = standard input, text)")
      ->required();
  sub->add_option("--input", args->input,
                  "text|f64|f32|capture (default: by extension, .f64/.bin = f64, .f32 = f32, .cap/.rigcap = capture, else "
                  "text)")
      ->check(CLI::IsMember({"auto", "text", "f64", "f32", "capture"}));
  sub->add_option("--data", args->data, "freq (accelerometer output, default) or phase (its integral)")
      ->check(CLI::IsMember({"freq", "frequency", "phase"}));
  sub->add_option("--rate", args->rate, "sample rate, Hz (default: capture header, else 1000, with a note)");
  sub->add_option("--taus", args->taus,
                  "tau grid: octave|decade|all|log:N (default log:100), or m:LIST, averaging factors (m:1,2,5)");
  sub->add_option("--dev", args->dev,
                  "extra statistics, comma-separated: one of adev|oadev|mdev|tdev|hdev|ohdev|totdev and any of "
                  "theo1|theoh|mtot|ttot|htot (OADEV always)");
  sub->add_option("--confidence", args->confidence, "confidence of the bounds (default one sigma, erf(1/sqrt 2) = 0.682689, Stable32's \"0.683\")");
  sub->add_flag("--no-bounds", args->no_bounds, "skip noise identification and bounds");
  sub->add_flag("--no-psd", args->no_psd, "skip the PSD (Allan part only)");
  sub->add_flag("--no-work-limit", args->no_work_limit,
                "--taus all on a long record: compute every factor however long it takes (refused beyond about 4e9 "
                "term sums without it)");
  sub->add_flag("--no-oadev", args->no_oadev,
                "with --dev: that deviation only, no OADEV and no noise terms (they are read from OADEV)");
  sub->add_option("--channel", args->channel, "capture channel: x (unfiltered, default) or y (filtered)");
  sub->add_option("--gaps", args->gaps,
                  "a capture with samples lost: join (default: analyse across the gaps as if contiguous, with a "
                  "warning), longest (the longest gap-free stretch) or stop (exit 2)")
      ->check(CLI::IsMember({"join", "longest", "stop"}));
  sub->add_option("--json", args->json_out, "write the analysis as JSON (docs/contracts.md shape)");
  sub->add_option("--svg", args->svg_dir,
                  "write allan.svg and psd.svg into this folder (made if missing, in a folder that exists)");
  sub->add_option("--window", args->window, "PSD window: hann|hamming|blackman|rect")->capture_default_str();
  sub->add_option("--segment", args->segment, "PSD segment length, at least 8 (default: chosen from the record)");
  sub->add_option("--overlap", args->overlap, "PSD segment overlap, fraction in [0, 0.95] (default 0.5)");
  sub->add_option("--threads", args->threads, "threads (default and 0: all cores)");
  sub->add_option("--memory-mib", args->memory_mib, "memory budget for streaming, 1..1048576 MiB (default 384)");
  sub->callback([args, &rc, sub] {
    if (const CLI::Option* r = sub->get_option("--rate"); r->count() > 0) args->rate_text = r->results().back();
    rc = run(*args);
  });
}

}  // namespace rig::cli
