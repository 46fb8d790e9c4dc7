// The rig's capture file: a self-describing header followed by CRC-checked
// blocks of samples, written as samples arrive. A process killed at any point
// leaves a file readable up to its last complete block; the reader reports
// what it recovered and where any damage lies. Format: docs/capture-format.md.
#pragma once
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rig/core/types.hpp"

namespace rig::capture {

inline constexpr char kMagic[8] = {'R', 'I', 'G', 'C', 'A', 'P', '1', '\n'};
inline constexpr uint32_t kBlockMagic = 0x314B4C42;  // "BLK1" little-endian
inline constexpr uint32_t kEndMagic = 0x31444E45;    // "END1"
inline constexpr std::size_t kRecordSize = 16;       // u32 seq, f32 x, f32 y, u32 status
inline constexpr std::size_t kBlockHeaderSize = 16;  // u32 magic, u32 count, u32 payload crc, u32 header crc
inline constexpr uint32_t kMaxBlockSamples = 1u << 20;
inline constexpr double kMaxRateHz = 1e6;  // a header rate outside [1 uHz, 1 MHz] is damage (the DUTs stream at 1 kHz)
// One sample in 11.6 days: below it nothing this rig records, and 5e-324 Hz gave infinite taus,
// exit 0 (a review).
inline constexpr double kMinRateHz = 1e-6;

struct Header {
  std::string serial;
  std::string phase;        // e.g. "run01-U10", "raw"
  std::string orientation;  // "U10" / "U20"
  std::string started;      // ISO 8601 UTC
  std::string units = "g";
  double rate_hz = 1000.0;
  nlohmann::json extra = nlohmann::json::object();  // profile name, plant, software, filter...
};

// What the reader found. `complete` = the writer closed the file normally
// (end marker present, sample count matches) and no block was damaged.
struct Recovery {
  uint64_t samples = 0;
  uint64_t blocks = 0;
  uint64_t damaged_blocks = 0;
  bool complete = false;
  bool truncated = false;  // ends without the end marker (writer killed or disk full)
  std::string problem;     // human-readable description of the first problem, empty if none
  std::vector<std::string> notes;  // one line per damage found ("offset 123456: block payload CRC mismatch")
  // Samples whose x or y is NaN or infinite in blocks with a valid CRC (e.g. a DUT that sent a
  // NaN float): counted, the first kMaxNonFiniteNotes located in `notes`; `complete` still
  // describes the file, so a reader that analyses the values must check this count.
  uint64_t non_finite = 0;
  // Samples with a finite x and a NaN y: how a stream without y is recorded (the reassembly's
  // y_g for a stream that carries none), so not damage; counted apart, the first one located.
  // Not for a capture whose header names its stream's y (extra.stream.y): non_finite there.
  uint64_t y_absent = 0;
  std::string first_y_absent;  // "offset N: sample K" of the first such sample
  static constexpr std::size_t kMaxNonFiniteNotes = 8;
  std::string summary(const std::string& path) const;
};

class Writer {
 public:
  // Creates `path` (an existing file is renamed to path + ".interrupted-N" so
  // no data is lost). Throws std::runtime_error naming the path on I/O errors.
  Writer(const std::string& path, const Header& header, uint32_t block_samples = 1000);
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  void append(std::span<const Sample> samples);
  // Writes the pending partial block (the kernel holds it even if the process dies next).
  void flush();
  // Flushes, writes the end marker, fsyncs, closes. Idempotent.
  void close();
  uint64_t samples_written() const { return total_; }
  const std::string& path() const { return path_; }
  // Where the file that was at `path` went (path + ".interrupted-N"), or "" when there was none.
  const std::string& set_aside() const { return set_aside_; }

 private:
  void write_block(const Sample* s, uint32_t n);
  void write_all(const void* p, std::size_t n);
  enum class Sync { kData, kAll };  // fdatasync (the samples), fsync (and the file's times)
  void sync(Sync what);             // throws on failure
  void sync_if_due();           // the minute's fdatasync (write_block counts the blocks)
  std::string path_, set_aside_;
  int fd_ = -1;
  uint32_t block_samples_;
  std::vector<Sample> pending_;
  std::vector<unsigned char> buf_;
  uint64_t total_ = 0;
  uint32_t blocks_since_sync_ = 0;
  uint64_t bytes_ = 0, started_ = 0;  // written; handed to the disk (sync_file_range)
  std::chrono::steady_clock::time_point last_sync_ = std::chrono::steady_clock::now();
};

class Reader {
 public:
  // Throws ConfigError naming the file when it is missing or its header is unreadable.
  explicit Reader(const std::string& path);
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  const Header& header() const { return header_; }
  // Reads the next samples (skipping damaged blocks, whose loss is flagged with
  // sample_status::kGapBefore on the next good sample). Returns 0 at the end.
  std::size_t read(std::span<Sample> out);
  // Complete after read() returned 0.
  const Recovery& recovery() const { return rec_; }
  const std::string& path() const { return path_; }
  // At most this many samples can follow the header (each takes 16 bytes of the file).
  uint64_t max_samples() const { return file_size_ > data_start_ ? (file_size_ - data_start_) / kRecordSize : 0; }

 private:
  bool next_block();
  bool resync(uint64_t from);
  void flag_non_finite(uint64_t block_pos);
  std::string path_;
  std::FILE* f_ = nullptr;
  uint64_t file_size_ = 0;
  uint64_t pos_ = 0;
  uint64_t data_start_ = 0;
  Header header_;
  Recovery rec_;
  std::vector<Sample> block_;
  std::size_t block_pos_ = 0;
  bool gap_pending_ = false;
  bool done_ = false;
  bool y_named_ = false;  // the header names the stream's y: a NaN y is then a non-finite value
  uint32_t prev_count_ = 0, prev_crc_ = 0;  // the last good block's, to notice a block written twice
};

// The file ends with a valid end marker (its writer closed it); no block is read. False for a
// file that cannot be read.
bool ends_closed(const std::string& path);

// Whole file into memory.
struct Loaded {
  Header header;
  std::vector<Sample> samples;
  Recovery recovery;
};
Loaded load(const std::string& path);

// Channel helpers for analysis.
std::vector<double> channel_x(std::span<const Sample> s);
std::vector<double> channel_y(std::span<const Sample> s);

// Samples lost between two consecutive records, from their sequence counters (the link's
// 32-bit counter wraps): 0 when `seq` follows `prev`, nullopt when it does not come after it
// (equal, or more than half the counter's period back: not a recording's order).
std::optional<uint32_t> lost_between(uint32_t prev, uint32_t seq);

}  // namespace rig::capture
