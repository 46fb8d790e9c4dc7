// The readers of `rig analyze`: raw float64 files, text (one value per line) and the rig's
// captures. Every value is checked before the analysis uses it: NaN, inf and values beyond
// analysis::kMaxMagnitude (2^333) are a configuration error (exit 2) naming the file and the value's
// position (value index and byte, line, or sample and capture offset). Text is decimal
// floating point as std::from_chars reads it (subnormals accepted, hex and "inf" not; a value
// beyond a double, or nearer 0 than its smallest subnormal, refused and said which).
#pragma once
#include <mutex>
#include <cstdint>
#include <istream>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/allan.hpp"
#include "rig/capture/capture.hpp"

namespace rig::cli {

// Raw little-endian float64 values. A file that fits `map_limit_bytes` is mapped and checked
// whole at open (one vectorised pass, in two halves on two threads from 2^19 values; the
// engine then reads it in place, without copies) or, with `check_in_pass`, by check_range()
// as the Allan engine's pass reaches each range (the values are read once, not twice: `rig
// analyze` makes that pass before anything else uses them);
// a larger one is read with pread and checked as it is first read (bounded memory for 50-h
// records; the engine's re-reads of a checked prefix are not checked again). read_at() never
// delivers a value that is not checked.
class F64File final : public analysis::ChunkSource {
 public:
  F64File(const std::string& path, std::size_t map_limit_bytes, bool check_in_pass = false);
  ~F64File() override;
  F64File(const F64File&) = delete;
  F64File& operator=(const F64File&) = delete;
  std::uint64_t size() const override { return n_; }
  std::size_t read_at(std::uint64_t pos, std::span<double> out) const override;
  const double* contiguous() const override { return map_; }
  void check_range(std::uint64_t pos, std::size_t len) const override;
  void will_read(std::uint64_t pos, std::size_t len) const override;

 private:
  void open_and_check(std::size_t map_limit_bytes, bool check_in_pass);
  void release() noexcept;
  void check(std::uint64_t pos, std::span<const double> v) const;
  void check_new(std::uint64_t pos, std::span<const double> v) const;
  void populate(std::uint64_t lo, std::uint64_t hi) const;
  void populate_and_check() const;
  std::string path_;
  int fd_ = -1;
  std::uint64_t n_ = 0;
  const double* map_ = nullptr;
  // What has been checked: values [0, checked_) and, while a second part of a split pass is
  // ahead of the first, [run_lo_, run_hi_) (merged into the prefix when the first reaches it).
  mutable std::mutex checked_mutex_;
  mutable std::uint64_t checked_ = 0, run_lo_ = 0, run_hi_ = 0;
};

// One value per line; '#' starts a comment; blank lines are skipped; ',' ';' and blanks around
// a value are ignored. Errors name path:line.
// What the input is, before it is read: a folder is refused (it used to read as "0 values"),
// and --input f64 and capture need a regular file (they are read by their size); text may come
// from a pipe or FIFO, read until its writer closes it (a FIFO waits for its writer, as any
// reader of one does); "-" is standard input, text only. A raw float file (f64, f32) whose first
// bytes are all text is a text record read as raw floats (its values would be nonsense): refused,
// `how` saying how the kind was chosen ("--input f64", "its .bin name"). ConfigError naming the path.
void check_input_path(const std::string& path, const std::string& input, const std::string& how = {});
// A value from a file quoted in a message: bytes that do not print (control bytes, NUL, DEL)
// and bytes that are not well-formed UTF-8 as \xNN, so a stray byte is seen rather than sent
// to the terminal; whole UTF-8 characters as they are.
std::string quoted_bytes(std::string_view s);
// path "-" reads standard input, its errors naming "stdin:LINE". blank_between (optional): the
// number of blank lines between two values (a row left empty, which may be a missing sample;
// the values around it are joined), for the caller to note.
std::vector<double> read_text(const std::string& path, std::size_t* blank_between = nullptr);
// A raw little-endian float32 file (what many DAQ tools and numpy's astype('<f4') write), widened
// to double exactly. A size that is not a multiple of 4, or a NaN or infinite value, is a
// ConfigError naming the file, the value's index and its byte offset.
std::vector<double> read_f32(const std::string& path);
std::vector<double> read_text(std::istream& in, const std::string& name, std::size_t* blank_between = nullptr);

// A break in a capture's sample sequence: values[at - 1] and values[at] were not consecutive
// samples (the link or the reader flagged samples lost before `at`, or the DUT's counter jumps).
struct CaptureGap {
  std::size_t at = 0;
  std::uint32_t seq_before = 0, seq_after = 0;
  std::uint64_t lost = 0;  // seq_after - seq_before - 1 (modulo 2^32); 0 when the counter does not say
};
struct CaptureData {
  std::vector<double> values;
  capture::Header header;
  capture::Recovery recovery;
  std::vector<CaptureGap> gaps;
  // The first sample read is flagged kGapBefore: samples before it were lost (the first block
  // damaged). Not a gap: nothing precedes it to be joined; the record just starts later.
  bool lost_at_start = false;
};
// One channel ("x" or "y") of a capture, with what the reader recovered and where the sample
// sequence breaks. A non-finite value in that channel is an error naming the sample and its
// offset in the file.
CaptureData read_capture(const std::string& path, const std::string& channel);

}  // namespace rig::cli
