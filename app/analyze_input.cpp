#include "app/analyze_input.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <optional>
#include <system_error>
#include <thread>
#include <vector>

#include "rig/core/escape.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/number_text.hpp"

namespace rig::cli {

namespace an = rig::analysis;

namespace {

// The shortest text that reads back as x ("1e+300", not "1.0000000000000001e+300": a review).
std::string shown(double x) { return shortest_text(x); }

// Why a value the checks refused is refused.
std::string refusal(double x) {
  return std::isfinite(x) ? shown(x) + " is beyond +-2^333 = 1.7e100 (not a measurement)" : shown(x) + " is not a finite number";
}

// What a refused raw file may be instead, by its first bytes: said only beside a refusal (a raw
// float file may start with any two bytes; a capture is refused at its magic before, below).
std::string another_format(std::string_view head) {
  return head.starts_with("\x1F\x8B") ? "; the file starts as gzip does: decompress it first (zcat FILE > record)" : "";
}
std::string head_of(int fd) {
  char b[8] = {};
  const ssize_t got = ::pread(fd, b, sizeof b, 0);
  return got > 0 ? std::string(b, static_cast<std::size_t>(got)) : std::string();
}
std::string another_format(int fd) { return another_format(head_of(fd)); }

// A raw float file that starts with the capture's eight magic bytes ("RIGCAP1\n") is a capture:
// as float32 its header and blocks read as finite nonsense, exit 0 (a newcomer's review). No
// record of measurements starts with those bytes.
void refuse_a_capture_read_raw(const std::string& path, std::string_view head, const char* as) {
  if (head.starts_with(std::string_view(capture::kMagic, sizeof capture::kMagic)))
    throw InputError(path + ": a capture file (rig.capture/1), not raw " + as + ": read it with --input capture");
}

}  // namespace

F64File::F64File(const std::string& path, std::size_t map_limit_bytes, bool check_in_pass) : path_(path) {
  try {
    open_and_check(map_limit_bytes, check_in_pass);
  } catch (...) {
    // A constructor that throws runs no destructor: without this, every refused file leaked
    // its descriptor and its mapping (found profiling tests/fuzz/fuzz_analyze_input.cpp).
    release();
    throw;
  }
}

void F64File::release() noexcept {
  if (map_) ::munmap(const_cast<double*>(map_), n_ * 8);
  if (fd_ >= 0) ::close(fd_);
  map_ = nullptr;
  fd_ = -1;
}

void F64File::open_and_check(std::size_t map_limit_bytes, bool check_in_pass) {
  const std::string& path = path_;
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw InputError(path + ": cannot open: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd_, &st) != 0) throw InputError(path + ": cannot stat: " + std::strerror(errno));
  refuse_a_capture_read_raw(path, head_of(fd_), "float64");
  if (st.st_size % 8 != 0)
    throw InputError(path + ": size " + std::to_string(st.st_size) + " bytes is not a multiple of 8 (float64)" +
                     another_format(fd_));
  n_ = static_cast<std::uint64_t>(st.st_size) / 8;
  const std::size_t bytes = static_cast<std::size_t>(st.st_size);
  if (bytes > 0 && bytes <= map_limit_bytes) {
    void* p = ::mmap(nullptr, bytes, PROT_READ, MAP_PRIVATE, fd_, 0);
    if (p != MAP_FAILED) {
      map_ = static_cast<const double*>(p);
      // check_in_pass: the pass's two threads fault the pages in (will_read: each its own part,
      // instead of 2-3 ms of serial work before the pass) and check the values.
      if (!check_in_pass) populate_and_check();
      return;
    }
  }
  ::posix_fadvise(fd_, 0, 0, POSIX_FADV_SEQUENTIAL);
}

F64File::~F64File() { release(); }

// The mapped file's page tables are filled in one call per part instead of one fault per
// 4 KiB (MADV_POPULATE_READ; a kernel before 5.14 refuses it and the check's reads fault the
// pages in), and every value is checked. Both take time proportional to the file and are
// serial work at the start of every analysis: a large file is done in two halves on two
// threads (3.6e6 values: about 6 ms of CPU before the deviations can start). The first
// unusable value of the file is the one reported, whichever half holds it.
void F64File::populate(std::uint64_t lo, std::uint64_t hi) const {
  // Page-aligned: the mapping starts on a page; the range is rounded out to whole pages.
  const std::uintptr_t page = static_cast<std::uintptr_t>(::sysconf(_SC_PAGESIZE));
  const auto a = reinterpret_cast<std::uintptr_t>(map_ + lo) / page * page;
  const auto b = reinterpret_cast<std::uintptr_t>(map_ + hi);
#ifdef MADV_POPULATE_READ
  ::madvise(reinterpret_cast<void*>(a), b - a, MADV_POPULATE_READ);  // advisory: failure only costs speed
#else
  (void)a, (void)b;
#endif
}

void F64File::populate_and_check() const {
  const auto part = [this](std::uint64_t lo, std::uint64_t hi) -> std::optional<std::size_t> {
    populate(lo, hi);
    const auto bad = an::first_unusable(std::span<const double>(map_ + lo, hi - lo));
    return bad ? std::optional<std::size_t>(lo + *bad) : std::nullopt;
  };
  constexpr std::uint64_t kSplitFrom = 1u << 19;  // 4 MiB: below it a thread costs more than it saves
  std::optional<std::size_t> bad;
  if (n_ < kSplitFrom || std::thread::hardware_concurrency() < 2) {
    bad = part(0, n_);
  } else {
    const std::uint64_t mid = n_ / 2;
    std::optional<std::size_t> bad_hi;
    {
      std::jthread upper([&] { bad_hi = part(mid, n_); });
      bad = part(0, mid);
    }
    if (!bad) bad = bad_hi;
  }
  if (bad) check(*bad, std::span<const double>(map_ + *bad, 1));
  checked_ = n_;
}

void F64File::will_read(std::uint64_t pos, std::size_t len) const {
  if (map_ && pos < n_) populate(pos, pos + std::min<std::uint64_t>(len, n_ - pos));
}

void F64File::check_range(std::uint64_t pos, std::size_t len) const {
  if (map_ && pos < n_) check_new(pos, std::span<const double>(map_ + pos, std::min<std::uint64_t>(len, n_ - pos)));
}

// Checks v (the values from pos) unless they are known checked, and records them: a range that
// continues the checked prefix extends it; one beyond it starts or continues the second run
// (the upper part of the engine's split pass), which joins the prefix once the prefix reaches
// it. Other ranges are checked again when read (cost only).
void F64File::check_new(std::uint64_t pos, std::span<const double> v) const {
  const std::uint64_t end = pos + v.size();
  {
    std::lock_guard lock(checked_mutex_);
    if (end <= checked_ || (pos >= run_lo_ && end <= run_hi_)) return;
  }
  check(pos, v);
  std::lock_guard lock(checked_mutex_);
  if (pos <= checked_) {
    checked_ = std::max(checked_, end);
  } else if (run_lo_ == run_hi_) {
    run_lo_ = pos, run_hi_ = end;
  } else if (pos >= run_lo_ && pos <= run_hi_) {
    run_hi_ = std::max(run_hi_, end);
  }
  if (run_lo_ < run_hi_ && checked_ >= run_lo_) {
    checked_ = std::max(checked_, run_hi_);
    run_lo_ = run_hi_ = 0;
  }
}

void F64File::check(std::uint64_t pos, std::span<const double> v) const {
  if (const auto bad = an::first_unusable(v))
    throw InputError(path_ + ": value " + std::to_string(pos + *bad) + " (counted from 0; byte " + std::to_string((pos + *bad) * 8) +
                     ") " + refusal(v[*bad]) + another_format(fd_));
}

std::vector<double> read_f32(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open: " + std::strerror(errno));
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::uint64_t>(in.tellg());
  in.seekg(0);
  char head[8] = {};
  in.read(head, sizeof head);
  const std::string_view first(head, static_cast<std::size_t>(in.gcount()));
  in.clear();
  in.seekg(0);
  refuse_a_capture_read_raw(path, first, "float32");
  if (size % 4 != 0)
    throw InputError(path + ": size " + std::to_string(size) + " bytes is not a multiple of 4 (float32)" +
                     another_format(first));
  std::vector<float> raw(size / 4);
  if (!in.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(size)))
    throw InputError(path + ": cannot read: " + std::strerror(errno));
  static_assert(std::endian::native == std::endian::little, "float32 files are little-endian, as this host");
  std::vector<double> v(raw.begin(), raw.end());  // every float is a double exactly
  if (const auto bad = an::first_unusable(v))
    throw InputError(path + ": value " + std::to_string(*bad) + " (counted from 0; byte " + std::to_string(*bad * 4) + ") " +
                     refusal(v[*bad]) + another_format(first));
  return v;
}

std::size_t F64File::read_at(std::uint64_t pos, std::span<double> out) const {
  if (pos >= n_) return 0;
  const std::size_t want = static_cast<std::size_t>(std::min<std::uint64_t>(out.size(), n_ - pos));
  if (map_) {  // checked at open, or in the engine's pass (else here)
    check_new(pos, std::span<const double>(map_ + pos, want));
    std::memcpy(out.data(), map_ + pos, want * 8);
    return want;
  }
  auto* p = reinterpret_cast<char*>(out.data());
  std::size_t got = 0;
  while (got < want * 8) {
    const ssize_t r = ::pread(fd_, p + got, want * 8 - got, static_cast<off_t>(pos * 8 + got));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0)
      throw InputError(path_ + ": read error at value " + std::to_string(pos + got / 8) + ": " +
                       (r < 0 ? std::strerror(errno) : "unexpected end"));
    got += static_cast<std::size_t>(r);
  }
  // Only values not yet checked are checked: the engine's cursors and far taus re-read what its
  // sequential pass has already read (and checked) many times over.
  check_new(pos, std::span<const double>(out.data(), want));
  return want;
}

namespace {
// How many bytes of s are not text: neither printable ASCII, tab nor CR, nor in well-formed UTF-8.
std::size_t binary_bytes(std::string_view s) {
  std::size_t bad = 0;
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    const std::size_t len = (c >= 0x20 && c < 0x7F) || c == '\t' || c == '\r' ? 1 : c >= 0x80 ? utf8_sequence_at(s, i) : 0;
    if (len == 0) ++bad;
    i += std::max<std::size_t>(len, 1);
  }
  return bad;
}

// A UTF-16 text file (Windows' "Unicode" text): its byte-order mark, then characters of two bytes
// whose one byte is 0 for ASCII. Its NULs got it past the text test of a raw read, and --input f32
// read it as float32 (OADEV 1.7e-39, exit 0: a metrologist's review); as text it was "not a decimal
// number" with a hint to read it raw. The mark's name ("\xFF\xFE") when head is one, else "".
std::string utf16_mark(std::string_view head) {
  if (head.size() < 4) return "";
  const bool le = head.starts_with("\xFF\xFE"), be = head.starts_with("\xFE\xFF");
  if (!le && !be) return "";
  std::size_t ascii = 0, chars = 0;
  for (std::size_t i = 2; i + 1 < head.size(); i += 2, ++chars) {
    const auto lo = static_cast<unsigned char>(head[le ? i : i + 1]), hi = static_cast<unsigned char>(head[le ? i + 1 : i]);
    ascii += hi == 0 && lo != 0 && lo < 0x80;
  }
  return 10 * ascii >= 9 * chars ? (le ? "\\xFF\\xFE" : "\\xFE\\xFF") : "";
}

// The refusal of a UTF-16 text file, with the conversion that makes it a record.
std::string utf16_refusal(const std::string& path, const std::string& mark) {
  return path + ": a UTF-16 text file (its first bytes " + mark +
         " are UTF-16's byte-order mark: Windows' \"Unicode\" text); a text record is read as UTF-8 or ASCII: convert it "
         "first, e.g. " +
         (path == "stdin" ? std::string("... | iconv -f UTF-16 -t UTF-8 | rig analyze - ...")
                          : "iconv -f UTF-16 -t UTF-8 '" + path + "' > record.txt");
}

// The raw floats' width, read off their bits. Float32 samples taken two at a time as one 8-byte
// value have two halves that are both normal float32 of like size; a float64's low half is
// mantissa bits, whose float32 exponent field is about uniform, so it is one by chance about one
// time in eight. Of the 8-byte groups of head: how many read as such float32 pairs
// (`f32_pairs`), and how many read as normal float64 within 2^16 of their median (`f64_like`).
struct RawWidth {
  std::size_t groups = 0, f32_pairs = 0, f64_like = 0;
};
RawWidth raw_width(std::string_view head) {
  RawWidth w;
  w.groups = head.size() / 8;
  std::vector<int> exp64;
  for (std::size_t g = 0; g < w.groups; ++g) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, head.data() + 8 * g, 8);  // little-endian, as the readers (static_assert above)
    const auto e_lo = static_cast<int>((bits >> 23) & 0xFF), e_hi = static_cast<int>((bits >> 55) & 0xFF);
    if (e_lo != 0 && e_lo != 0xFF && e_hi != 0 && e_hi != 0xFF && std::abs(e_lo - e_hi) <= 16) ++w.f32_pairs;
    const auto e = static_cast<int>((bits >> 52) & 0x7FF);
    if (e != 0 && e != 0x7FF) exp64.push_back(e);
  }
  if (!exp64.empty()) {
    std::nth_element(exp64.begin(), exp64.begin() + static_cast<std::ptrdiff_t>(exp64.size() / 2), exp64.end());
    const int median = exp64[exp64.size() / 2];
    w.f64_like = static_cast<std::size_t>(std::count_if(exp64.begin(), exp64.end(), [&](int e) { return std::abs(e - median) <= 16; }));
  }
  return w;
}
}  // namespace

void check_input_path(const std::string& path, const std::string& input, const std::string& how) {
  if (path == "-") {  // standard input: read as it comes, so text only
    if (input != "text")
      throw InputError("-: standard input carries --input text only (--input " + input +
                       " is read by its size: give the file)");
    return;
  }
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw InputError(path + ": cannot open: " + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) throw InputError(path + ": is a folder, not a record (give one file)");
  if (!S_ISREG(st.st_mode) && input != "text")
    throw InputError(path + ": not a regular file: --input " + input +
                     " is read by its size (a pipe or FIFO can carry --input text)");
  if (input == "f64" || input == "f32") {
    // Raw floats' bytes are all text by chance with a probability of about (100/256)^bytes; a text
    // record read as them gave nonsense values without a word (a review: OADEV 8.5e-34 of a text
    // file named .bin).
    std::ifstream in(path, std::ios::binary);
    std::string head(4096, '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<std::size_t>(in.gcount()));
    if (const std::string mark = utf16_mark(head); !mark.empty()) throw InputError(utf16_refusal(path, mark));
    // Text as the text reader reads it (ASCII, tab, CR, well-formed UTF-8) and the line ends;
    // judged on 16 bytes or more, or on a file too short for 3 raw values, refused anyway (an
    // 8-byte "1\n2\n3\n4\n" read as float64 was "1 value; at least 3 are needed": a review).
    const bool too_short = head.size() < (input == "f64" ? 24u : 12u);
    const bool text = (head.size() >= 16 || (too_short && !head.empty())) &&
                      binary_bytes(head) == static_cast<std::size_t>(std::count(head.begin(), head.end(), '\n'));
    // What the file was read as and the bytes looked at, as the refusal and the warnings say it.
    const std::string read_as = path + ": read as raw " + (input == "f64" ? "float64" : "float32") + " (" +
                                (how.empty() ? "--input " + input : how) + "), but " +
                                (head.size() < 4096 ? "all its " : "its first ") + std::to_string(head.size()) + " bytes ";
    if (text) {
      // Its first line that holds anything, as the file's start shows it.
      const std::size_t from = std::min(head.find_first_not_of(" \t\r\n"), head.size());
      const std::size_t eol = std::min(head.find_first_of("\r\n", from), head.size());
      throw InputError(read_as + "are text (\"" + quoted_bytes(head.substr(from, std::min<std::size_t>(eol - from, 40))) +
                       "\"): a text record, one value per line, is read with --input text");
    }
    // The other width: nonsense values of a plausible size (a float32 record of 0.98 g read as
    // float64 gave 0.0039 g with deviations of 6e-7, exit 0; a review). Warned, not refused: the
    // bits are evidence, not proof (9 in 10 groups as the other width's, fewer than 1 in 4 as this
    // one's; a float64 record's groups read as float32 pairs about 1 in 8, but a constant's low
    // halves are one value, and a float32 record with every other sample 0 reads as float64 of
    // like size: a review found both refused).
    const RawWidth w = raw_width(head);
    const std::string start = "rig: warning: " + read_as;
    if (w.groups >= 16 && input == "f64" && 10 * w.f32_pairs >= 9 * w.groups)
      std::cerr << start << "look like float32 values: " << w.f32_pairs << " of their " << w.groups
                << " 8-byte values are two float32 of like size (a float64's low half is mantissa bits); if the record "
                   "is float32, read it with --input f32\n";
    if (w.groups >= 16 && input == "f32" && 4 * w.f32_pairs < w.groups && 10 * w.f64_like >= 9 * w.groups)
      std::cerr << start << "look like float64 values: " << w.f64_like << " of their " << w.groups
                << " 8-byte values are float64 of like size, and only " << w.f32_pairs
                << " read as two float32 of like size; if the record is float64, read it with --input f64\n";
  }
}

namespace {
// A line of a binary file (a raw float64 file read as text): a NUL byte, or, in 16 bytes or
// more (a Latin-1 unit is not binary), more than a quarter of its bytes not text.
bool looks_binary(std::string_view line) {
  return line.find('\0') != std::string_view::npos || (line.size() >= 16 && 4 * binary_bytes(line) > line.size());
}

// A refused value as quoted in a message: whole when short, else its first bytes and its length
// (a binary file's "line" of hundreds of bytes filled the terminal with \xNN, a review).
std::string excerpt(std::string_view tok) {
  constexpr std::size_t kMaxQuoted = 40;
  if (tok.size() <= kMaxQuoted) return "'" + quoted_bytes(tok) + "'";
  const std::size_t cut = utf8_cut(tok, kMaxQuoted, kMaxQuoted - 3);  // whole characters
  return "'" + quoted_bytes(tok.substr(0, cut)) + "...' (" + std::to_string(tok.size()) + " bytes)";
}

// Whether a decimal number std::from_chars found out of a double's range is too near 0 (it
// underflows) rather than too large: by the place of its first significant digit and its exponent.
bool underflows(std::string_view num) {
  const std::size_t e = num.find_first_of("eE");
  const std::string_view mantissa = num.substr(0, e);
  long long exponent = 0;
  if (e != std::string_view::npos) {
    std::string_view ex = num.substr(e + 1);
    if (!ex.empty() && ex[0] == '+') ex.remove_prefix(1);
    const auto [p, ec] = std::from_chars(ex.data(), ex.data() + ex.size(), exponent);
    if (ec == std::errc::result_out_of_range) return ex[0] == '-';  // beyond any long long: its sign decides
  }
  const std::size_t point = std::min(mantissa.find('.'), mantissa.size());
  const std::size_t first = mantissa.find_first_of("123456789");
  if (first == std::string_view::npos) return true;  // all zeros: from_chars would not have refused it
  // The decimal place of the first significant digit: 0 for units, -1 for tenths.
  const long long place = first < point ? static_cast<long long>(point - first) - 1 : -static_cast<long long>(first - point);
  return exponent + place < 0;
}
}  // namespace

// As every message shows text (rig/core/escape.hpp, shown_text): printable ASCII and whole UTF-8
// characters as they are, control bytes, malformed UTF-8 and characters a terminal acts on or
// shows as nothing as \xNN.
std::string quoted_bytes(std::string_view s) { return shown_text(s); }

namespace {
std::vector<double> read_lines(std::istream& in, const std::string& path, bool from_stdin, std::size_t* blank_between);
}  // namespace

std::vector<double> read_text(const std::string& path, std::size_t* blank_between) {
  if (path == "-") {
    // An ifstream on the descriptor, not std::cin: cin, synced with C stdio, reads a third as fast.
    if (::isatty(STDIN_FILENO)) std::cerr << "rig analyze: reading values from standard input (end with Ctrl-D)\n";
    std::ifstream in("/dev/stdin");
    if (!in) throw InputError(std::string("stdin: cannot open: ") + std::strerror(errno));
    return read_lines(in, "stdin", true, blank_between);
  }
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open: " + std::strerror(errno));
  return read_text(in, path, blank_between);
}

namespace {
// Characters a spreadsheet or word processor writes in numbers that look like ASCII ones but are
// not: quoted as they are, '1\xC2\xA0' read as '1 ' and '\u2212 1' as '-1' (a metrologist's review).
constexpr std::pair<std::string_view, std::string_view> kLookalikes[] = {
    {"\xC2\xA0", "a no-break space (U+00A0, bytes \\xC2\\xA0)"},
    {"\xE2\x80\xAF", "a narrow no-break space (U+202F, bytes \\xE2\\x80\\xAF)"},
    {"\xE2\x80\x89", "a thin space (U+2009, bytes \\xE2\\x80\\x89)"},
    {"\xE2\x88\x92", "a minus sign (U+2212, bytes \\xE2\\x88\\x92), not the ASCII '-'"},
};

// Digits grouped by blanks as the SI Brochure writes them (5.4.4: threes counted from the decimal
// marker both ways, "43 279.168 29", "0.981 234", "12 345.678"): the first integer group 1 to 3
// digits, the others 3; the fraction's groups 3, its last 1 to 3. Two columns' cut would keep a
// number's last digits only (awk's $2 of "0.981 234" is 234: a metrologist's review); "1 .5" and
// "0.5 700" are not such groups (a code review, a re-test).
bool si_grouped(std::string_view tok) {
  if (!tok.empty() && (tok[0] == '-' || tok[0] == '+')) tok.remove_prefix(1);
  std::vector<std::string_view> g;
  for (std::size_t at = 0; at <= tok.size();) {
    const std::size_t end = std::min(tok.find(' ', at), tok.size());
    g.push_back(tok.substr(at, end - at));
    at = end + 1;
  }
  if (g.size() < 2) return false;
  const auto digits = [](std::string_view s, std::size_t lo, std::size_t hi) {
    return s.size() >= lo && s.size() <= hi && s.find_first_not_of("0123456789") == std::string_view::npos;
  };
  std::size_t point_at = g.size();  // the group holding the decimal point, if any
  for (std::size_t i = 0; i < g.size(); ++i)
    if (const std::size_t p = g[i].find('.'); p != std::string_view::npos) {
      if (point_at != g.size() || g[i].find('.', p + 1) != std::string_view::npos) return false;
      point_at = i;
    }
  const std::size_t last = g.size() - 1;
  for (std::size_t i = 0; i < g.size(); ++i) {
    const std::size_t p = i == point_at ? g[i].find('.') : std::string_view::npos;
    const std::string_view whole = i <= point_at ? g[i].substr(0, p) : std::string_view();
    const std::string_view frac = i == point_at ? g[i].substr(p + 1) : i > point_at ? g[i] : std::string_view();
    if (i <= point_at && !(i == 0 ? digits(whole, 1, 3) : digits(whole, 3, 3))) return false;
    if (i >= point_at && !(i < last ? digits(frac, 3, 3) : digits(frac, 1, 3))) return false;
  }
  return true;
}

// Why a line that is not a decimal number is refused: the value quoted (an excerpt), and what
// the line looks like where it says more than the value (a binary file, a byte-order mark).
std::string not_a_number(std::string_view line, std::string_view tok, bool from_stdin) {
  std::string why = "not a decimal number: " + excerpt(tok);
  const auto lookalike = std::find_if(std::begin(kLookalikes), std::end(kLookalikes),
                                      [tok](const auto& l) { return tok.find(l.first) != std::string_view::npos; });
  // Standard input carries text only: the hint is the file's path (a review: "- --input f64",
  // as the file's hint said, is refused).
  if (looks_binary(line) && from_stdin)
    why += "; the input looks binary: raw float64 or float32 is read from its file (give the file's path with --input "
           "f64 or --input f32; standard input carries text only)";
  else if (looks_binary(line)) why += "; the file looks binary (raw float64 is read with --input f64, raw float32 with --input f32)";
  else if (lookalike != std::end(kLookalikes))
    why += std::string("; it holds ") + std::string(lookalike->second) +
           ", which spreadsheets and word processors write in numbers: the record's numbers take ASCII digits, "
           "'-', '.' and 'e' only";
  else if (si_grouped(tok)) {
    std::string joined(tok);
    std::erase(joined, ' ');
    why += "; digits grouped with blanks? the record's numbers are written without grouping (" + joined +
           "); two columns? a text record holds one value per line";
  }
  // The column separator: ';' or a blank before ',', which may be a decimal comma in the same
  // row ("0,5;1,2": a code review saw the cut on ',' recommended there).
  else if (const auto at = tok.find(';') != std::string_view::npos     ? tok.find(';')
                           : tok.find_first_of(" \t") != std::string_view::npos ? tok.find_first_of(" \t")
                                                                              : tok.find(',');
           at != std::string_view::npos) {
    // "1,5": digits, one comma, digits is a decimal comma as often as two columns; neither is
    // read, and the hint must not be a cut that turns 1,5 into 5 (an instrument engineer's review).
    const bool digits_comma_digits =
        tok[at] == ',' && at > 0 && at + 1 < tok.size() &&
        tok.find_first_not_of("+-0123456789", 0) == at && tok.find_first_not_of("0123456789", at + 1) == std::string_view::npos;
    if (digits_comma_digits) {
      std::string pointed(tok);
      pointed[at] = '.';
      why += "; a decimal comma? the record's numbers take a decimal point (" + pointed +
             "); two columns? a text record holds one value per line";
    }
    else {  // A table's row ("t,a", "0.1 0.2"): the record is one value per line (a metrologist's review).
      // Blanks around a ',' ("1 ,5", "1 , 5") pad it: the column separator is the ',' (awk's
      // second field of "1 ,5" is ",5", itself refused: a re-read).
      const std::size_t before = tok.find_last_not_of(" \t", at), after = tok.find_first_not_of(" \t", at);
      const char sep = tok[at] == ' ' || tok[at] == '\t'
                           ? ((before != std::string_view::npos && tok[before] == ',') ||
                                      (after != std::string_view::npos && tok[after] == ',')
                                  ? ','
                                  : ' ')
                           : tok[at];
      why += std::string("; a text record holds one value per line (take the column out first, e.g. ") +
             (sep == ',' ? "cut -d, -f2" : sep == ';' ? "cut -d';' -f2" : "awk '{print $2}'") + ")" +
             (sep != ',' && tok.find(',') != std::string_view::npos
                  ? "; its ',' may be a decimal comma: the record's numbers take a decimal point"
                  : "");
    }
  }
  else if (tok.find("\xEF\xBB\xBF") != std::string_view::npos)
    why += " (\\xEF\\xBB\\xBF is a byte-order mark, skipped only at the start of the file: two files joined?)";
  return why;
}
}  // namespace

std::vector<double> read_text(std::istream& in, const std::string& path, std::size_t* blank_between) {
  return read_lines(in, path, false, blank_between);
}

namespace {
// `from_stdin`: the lines are standard input's, whose hints name a file instead (it carries text only).
std::vector<double> read_lines(std::istream& in, const std::string& path, bool from_stdin, std::size_t* blank_between) {
  std::vector<double> v;
  std::string buffer;
  std::size_t blank = 0, blank_run = 0;  // blank lines since the last value (a comment line is not one)
  for (std::size_t lineno = 1; std::getline(in, buffer); ++lineno) {
    std::string_view line = buffer;  // the whole line stays in `buffer` for a message
    // A capture file given without --input capture: say so, not "not a decimal number: 'RIGCAP1'".
    if (lineno == 1 && line == std::string_view(capture::kMagic, sizeof capture::kMagic - 1))
      throw InputError(path + ": a capture file (rig.capture/1): read it with --input capture");
    // gzip's magic: no text starts with it (said as such, not as a binary float file: a review).
    if (lineno == 1 && line.starts_with("\x1F\x8B"))
      throw InputError(path + ": a gzip file: decompress it first (zcat FILE > record, or zcat FILE | rig analyze -)");
    // A UTF-8 byte-order mark, which Windows editors write at the start, is no part of the data.
    if (lineno == 1 && line.starts_with("\xEF\xBB\xBF")) line.remove_prefix(3);
    // UTF-16's byte-order mark: bytes no UTF-8 text starts with, so the mark alone says it (a file
    // whose first line is blank has nothing after the mark on this line to look at: a code review).
    if (lineno == 1 && (line.starts_with("\xFF\xFE") || line.starts_with("\xFE\xFF")))
      throw InputError(utf16_refusal(path, line[0] == '\xFF' ? "\\xFF\\xFE" : "\\xFE\\xFF"));
    // A CR before the line's end: lines ended by CR alone (classic Mac OS), read as one line, or a
    // comment that would swallow every value after it (a newcomer's review: "# x\r4\r5\r" lost
    // two values, exit 0). Refused, naming the line, before a comment is cut.
    if (const auto cr = line.find('\r'); cr != std::string_view::npos && cr + 1 < line.size())
      throw InputError(path + ":" + std::to_string(lineno) + ": a CR inside the line (" + excerpt(line) +
                       "): its lines end in CR alone (classic Mac OS)? end them in LF first, e.g. tr '\\r' "
                       "'\\n' < FILE > record");
    const auto hash = line.find('#');
    const bool comment = hash != std::string_view::npos;
    if (comment) line = line.substr(0, hash);
    const auto b = line.find_first_not_of(" \t\r,;");
    if (b == std::string_view::npos) {
      if (!comment && !v.empty()) ++blank_run;
      continue;
    }
    blank += blank_run, blank_run = 0;  // only those with a value after them: not trailing ones
    const auto e = line.find_last_not_of(" \t\r,;");
    const std::string_view tok = line.substr(b, e - b + 1);
    const auto where = [&] { return path + ":" + std::to_string(lineno) + ": "; };
    // Around the value only blanks, and after it one ',' or ';' (a CSV's single column): ",5" is
    // a row whose first column is empty, "1,," one with empty columns after it; both were read as
    // a value (an instrument engineer's review).
    const auto separators = [](std::string_view s) {
      return static_cast<std::size_t>(std::count_if(s.begin(), s.end(), [](char c) { return c == ',' || c == ';'; }));
    };
    if (separators(line.substr(0, b)) > 0)
      throw InputError(where() + excerpt(buffer) + ": an empty column before the value (a text record holds one value "
                                                   "per line, a CSV's single column)");
    if (separators(line.substr(e + 1)) > 1)
      throw InputError(where() + excerpt(buffer) + ": empty columns after the value (a text record holds one value per "
                                                   "line, followed by at most one ',' or ';')");
    // from_chars reads decimal floating point only ("0x10" stops after the 0), has no leading
    // '+', and takes subnormals such as 1e-310 (strtod flags those ERANGE).
    const std::string_view num = tok.size() > 1 && tok[0] == '+' && tok[1] != '-' ? tok.substr(1) : tok;
    double x = 0;
    const auto [end, ec] = std::from_chars(num.data(), num.data() + num.size(), x);
    if (ec == std::errc::result_out_of_range && end == num.data() + num.size())
      throw InputError(where() + excerpt(tok) +
                       (underflows(num) ? " is nearer 0 than the smallest double, 4.9e-324 (not a measurement)"
                                         : " is beyond the range of a double"));
    if (ec != std::errc() || end != num.data() + num.size()) throw InputError(where() + not_a_number(buffer, tok, from_stdin));
    if (!(std::fabs(x) < an::kMaxMagnitude)) throw InputError(where() + excerpt(tok) + ": " + refusal(x));
    v.push_back(x);
  }
  if (blank_between) *blank_between = blank;
  return v;
}
}  // namespace

// The capture reader's own refusals (not a capture, a header CRC mismatch) are the record's
// (a re-test: they still read "configuration error").
capture::Reader open_capture(const std::string& path) {
  try {
    return capture::Reader(path);
  } catch (const ConfigError& e) {
    throw InputError(e.what());
  }
}

CaptureData read_capture(const std::string& path, const std::string& channel) {
  capture::Reader r = open_capture(path);
  CaptureData c;
  c.header = r.header();
  std::vector<Sample> buf(4096);  // 64 KiB: large enough to amortise the calls, small to zero-fill
  std::uint32_t prev = 0;
  for (std::size_t n; (n = r.read(buf)) > 0;)
    for (std::size_t i = 0; i < n; ++i) {
      const Sample& s = buf[i];
      if (c.values.empty()) c.lost_at_start = (s.status & sample_status::kGapBefore) != 0;
      else if ((s.status & sample_status::kGapBefore) || s.seq != prev + 1u) {
        const std::optional<std::uint32_t> lost = capture::lost_between(prev, s.seq);
        // A counter that goes back (or repeats) is no gap: the samples are out of a recording's
        // order, and joining them would analyse a time series that never was (a review: two
        // swapped blocks read as "2000 samples lost", exit 0). A resume refuses the same capture.
        if (!lost)
          throw InputError(path + ": sample " + std::to_string(c.values.size()) + ": the sequence counter " +
                           (s.seq == prev ? "repeats" : "goes back") + " (" + std::to_string(prev) + " then " +
                           std::to_string(s.seq) +
                           "): the samples are not in a recording's order (blocks moved, or two recordings joined); "
                           "nothing analysed");
        c.gaps.push_back({c.values.size(), prev, s.seq, *lost});
      }
      prev = s.seq;
      c.values.push_back(channel == "y" ? s.y_g : s.x_g);
    }
  c.recovery = r.recovery();
  if (channel == "y" && c.recovery.y_absent > 0 && c.recovery.y_absent == c.values.size())
    throw InputError(path + ": channel y is NaN on every sample (a stream without y): nothing to analyse; analyse x");
  if (const auto bad = an::first_unusable(c.values)) {
    std::string where;
    for (const auto& note : c.recovery.notes)  // the reader located the first ones by file offset
      if (note.find(": sample " + std::to_string(*bad) + " ") != std::string::npos) where = " (" + note + ")";
    throw InputError(path + ": sample " + std::to_string(*bad) + " (counted from 0) of channel " + channel + " " +
                     refusal(c.values[*bad]) + where + "; " + std::to_string(c.recovery.non_finite) +
                     " sample(s) with a non-finite value in the capture" +
                     (c.recovery.y_absent ? ", " + std::to_string(c.recovery.y_absent) + " with y NaN" : ""));
  }
  return c;
}

}  // namespace rig::cli
