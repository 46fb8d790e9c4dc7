#include "rig/capture/capture.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <bit>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <new>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "rig/core/errors.hpp"
#include "rig/core/huge_pages.hpp"
#include "rig/core/json_unique.hpp"
#include "rig/core/set_aside.hpp"

namespace rig::capture {

static_assert(std::endian::native == std::endian::little, "capture files are little-endian; port the codec");
static_assert(sizeof(Sample) == kRecordSize, "Sample must match the 16-byte record layout");

namespace {

uint32_t crc(const void* p, std::size_t n) {
  return static_cast<uint32_t>(crc32(0L, static_cast<const Bytef*>(p), static_cast<uInt>(n)));
}

void put_u32(unsigned char* p, uint32_t v) { std::memcpy(p, &v, 4); }
uint32_t get_u32(const unsigned char* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}

std::string errno_text() { return std::strerror(errno); }

nlohmann::json header_json(const Header& h) {
  return {{"format", "rig.capture/1"},
          {"serial", h.serial},
          {"phase", h.phase},
          {"orientation", h.orientation},
          {"started", h.started},
          {"units", h.units},
          {"rate_hz", h.rate_hz},
          {"record", "u32 seq, f32 x, f32 y, u32 status (little-endian, 16 bytes)"},
          {"extra", h.extra}};
}

constexpr std::size_t align16(std::size_t n) { return (n + 15) & ~std::size_t{15}; }

}  // namespace

std::string Recovery::summary(const std::string& path) const {
  std::ostringstream os;
  os << path << ": " << samples << " samples in " << blocks << " blocks";
  if (complete) {
    os << ", complete";
  } else {
    os << ", INCOMPLETE";
    if (!problem.empty()) os << " (" << problem << ")";
  }
  if (damaged_blocks) os << "; " << damaged_blocks << " damaged block(s) skipped";
  if (non_finite) os << "; " << non_finite << " sample(s) with a non-finite value (NaN or inf)";
  if (y_absent > 0 && y_absent == samples) os << "; y is NaN on every sample (a stream without y)";
  else if (y_absent > 0) os << "; " << y_absent << " sample(s) with y NaN (x finite), the first at " << first_y_absent;
  return os.str();
}

// ---------------------------------------------------------------- Writer

Writer::Writer(const std::string& path, const Header& header, uint32_t block_samples)
    : path_(path), block_samples_(block_samples) {
  if (block_samples_ == 0 || block_samples_ > kMaxBlockSamples) throw std::invalid_argument("capture: bad block size");
  set_aside_ = rig::set_aside(path);  // keep whatever an interrupted attempt left
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd_ < 0) throw std::runtime_error("cannot create capture " + path + ": " + errno_text());
  const std::string js = header_json(header).dump();
  std::vector<unsigned char> h(align16(16 + js.size()), 0);
  std::memcpy(h.data(), kMagic, 8);
  put_u32(h.data() + 8, static_cast<uint32_t>(js.size()));
  put_u32(h.data() + 12, crc(js.data(), js.size()));
  std::memcpy(h.data() + 16, js.data(), js.size());
  write_all(h.data(), h.size());
  bytes_ = h.size();
  pending_.reserve(block_samples_);
}

Writer::~Writer() {
  try {
    close();
  } catch (...) {  // destructor must not throw; close() errors were already reportable via close()
  }
}

void Writer::write_all(const void* p, std::size_t n) {
  const char* c = static_cast<const char*>(p);
  while (n > 0) {
    const ssize_t w = ::write(fd_, c, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error("write to capture " + path_ + " failed: " + errno_text());
    }
    c += w;
    n -= static_cast<std::size_t>(w);
  }
}

void Writer::write_block(const Sample* s, uint32_t n) {
  // One write() per block: header and payload reach the page cache together,
  // so a killed process leaves at most one incomplete block at the end.
  buf_.resize(kBlockHeaderSize + std::size_t{n} * kRecordSize);
  std::memcpy(buf_.data() + kBlockHeaderSize, s, std::size_t{n} * kRecordSize);
  put_u32(buf_.data(), kBlockMagic);
  put_u32(buf_.data() + 4, n);
  put_u32(buf_.data() + 8, crc(buf_.data() + kBlockHeaderSize, std::size_t{n} * kRecordSize));
  put_u32(buf_.data() + 12, crc(buf_.data(), 12));
  write_all(buf_.data(), buf_.size());
  total_ += n;
  bytes_ += buf_.size();
  // The disk's write of every whole page so far started without waiting for it (only pages not
  // yet started: a page under writeback would hold up the next write into it), so the syncs find
  // little left to wait for: a `paper` run's main thread spent 0.38 s in them before, 0.20 s
  // with this and the once-a-second rule below (strace -T, 2026-12-06).
  if (const uint64_t whole = bytes_ & ~uint64_t{4095}; whole > started_ + (uint64_t{1} << 17)) {
    ::sync_file_range(fd_, static_cast<off_t>(started_), static_cast<off_t>(whole - started_), SYNC_FILE_RANGE_WRITE);
    started_ = whole;
  }
  ++blocks_since_sync_;
}

void Writer::sync_if_due() {
  // Bound what a power loss can take: about a minute of samples at 1 kHz, and where the samples
  // come faster than the wall clock (the emulated plant records a minute in about 30 ms: 90 syncs
  // in a `paper` run) a second of the rig's work. A phase the loss cuts is recorded again on resume.
  // Called once the written block has left pending_: a sync that fails must not leave it there
  // for close() to write a second time (a review).
  if (blocks_since_sync_ < 60) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_sync_ < std::chrono::seconds(1)) return;
  last_sync_ = now;
  blocks_since_sync_ = 0;
  sync(Sync::kData);
}

void Writer::sync(Sync what) {
  // A disk that fails to keep the samples says so here (EIO; NFS and some FUSE filesystems report
  // a full disk only now): a capture is never called recorded on an unchecked sync. EINVAL: a file
  // that cannot be synced (not a disk's), where there is nothing to wait for.
  const int rc = what == Sync::kAll ? ::fsync(fd_) : ::fdatasync(fd_);
  if (rc != 0 && errno != EINVAL)
    throw std::runtime_error("write to capture " + path_ + " failed (" + (what == Sync::kAll ? "fsync" : "fdatasync") +
                             "): " + errno_text());
}

void Writer::append(std::span<const Sample> samples) {
  if (fd_ < 0) throw std::runtime_error("capture " + path_ + " is closed");
  std::size_t i = 0;
  // Fast path: whole blocks straight from the caller's buffer.
  while (pending_.empty() && samples.size() - i >= block_samples_) {
    write_block(samples.data() + i, block_samples_);
    i += block_samples_;
    sync_if_due();
  }
  for (; i < samples.size(); ++i) {
    pending_.push_back(samples[i]);
    if (pending_.size() == block_samples_) {
      write_block(pending_.data(), block_samples_);
      pending_.clear();
      sync_if_due();
    }
  }
}

void Writer::flush() {
  if (fd_ < 0 || pending_.empty()) return;
  write_block(pending_.data(), static_cast<uint32_t>(pending_.size()));
  pending_.clear();
}

bool ends_closed(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  unsigned char end[16];
  const bool read = std::fseek(f, -16, SEEK_END) == 0 && std::fread(end, 1, sizeof end, f) == sizeof end;
  std::fclose(f);
  return read && get_u32(end) == kEndMagic && crc(end, 12) == get_u32(end + 12);
}

void Writer::close() {
  if (fd_ < 0) return;
  try {
    flush();
    unsigned char end[16];
    put_u32(end, kEndMagic);
    put_u32(end + 4, static_cast<uint32_t>(total_ & 0xffffffffu));
    put_u32(end + 8, static_cast<uint32_t>(total_ >> 32));
    put_u32(end + 12, crc(end, 12));
    write_all(end, sizeof end);
    sync(Sync::kAll);
  } catch (...) {  // closed all the same: the destructor's second close() would write a second end
    ::close(fd_);
    fd_ = -1;
    throw;
  }
  const int fd = fd_;
  fd_ = -1;  // closed once, whatever close() says
  if (::close(fd) != 0 && errno != EINTR)
    throw std::runtime_error("write to capture " + path_ + " failed (close): " + errno_text());
}

// ---------------------------------------------------------------- Reader

Reader::Reader(const std::string& path) : path_(path) {
  f_ = std::fopen(path.c_str(), "rb");
  if (!f_) throw ConfigError(path + ": cannot open capture: " + errno_text());
  // A constructor that throws runs no destructor: close the file on every error below, or
  // each rejected file would leak a descriptor and its 1 MiB buffer (found by fuzz_capture).
  struct CloseOnThrow {
    std::FILE*& f;
    bool armed = true;
    ~CloseOnThrow() {
      if (armed && f) std::fclose(f), f = nullptr;
    }
  } guard{f_};
  std::setvbuf(f_, nullptr, _IOFBF, 1 << 20);
  struct stat st {};
  ::fstat(::fileno(f_), &st);
  file_size_ = static_cast<uint64_t>(st.st_size);
  unsigned char h[16];
  if (std::fread(h, 1, 16, f_) != 16) throw ConfigError(path + ": not a rig capture (shorter than its header)");
  if (std::memcmp(h, kMagic, 8) != 0) throw ConfigError(path + ": not a rig capture (bad magic at offset 0)");
  const uint32_t len = get_u32(h + 8);
  const uint32_t want_crc = get_u32(h + 12);
  if (len > (1u << 20))
    throw ConfigError(path + ": capture header length " + std::to_string(len) + " is invalid (offset 8)");
  // A length the file is too short for: the file was cut, not its length field (a review read
  // "length 328 is invalid" on a capture cut at 100 bytes).
  if (16 + uint64_t{len} > file_size_)
    throw ConfigError(path + ": capture header truncated: its length says " + std::to_string(len) + " bytes from offset 16, the file has " +
                      std::to_string(file_size_) + " bytes (a file cut short?)");
  std::string js(len, '\0');
  if (std::fread(js.data(), 1, len, f_) != len) throw ConfigError(path + ": capture header truncated");
  if (crc(js.data(), len) != want_crc) throw ConfigError(path + ": capture header CRC mismatch (offset 16)");
  try {
    const auto j = parse_json_unique_keys(js);  // rate_hz twice was read at its second rate (a review)
    if (!j.is_object()) throw ConfigError(path + ": capture header is " + j.type_name() + ", not a JSON object");
    // The text fields, each named when it is not text (tools/rigcap.py says the same).
    const auto text = [&](const char* key) -> std::string {
      if (!j.contains(key)) return "";
      if (!j[key].is_string())
        throw ConfigError(path + ": capture header field " + key + " is " + j[key].dump() + ", not a string");
      return j[key].get<std::string>();
    };
    header_.serial = text("serial");
    header_.phase = text("phase");
    header_.orientation = text("orientation");
    header_.started = text("started");
    // What the samples mean is stated, never guessed: a format this reader does not know, units
    // other than the g every rig capture holds, or no rate are refused (a missing rate read as
    // 1000 Hz would put every tau of an analysis off by the true rate's ratio).
    if (j.contains("format") && j["format"] != "rig.capture/1")
      throw ConfigError(path + ": capture header format is " + j["format"].dump() +
                        ", not \"rig.capture/1\" (written by another program or version?)");
    header_.units = j.contains("units") ? text("units") : "g";
    if (header_.units != "g")
      throw ConfigError(path + ": capture header units is \"" + header_.units + "\", not \"g\" (a rig capture's samples are in g)");
    if (!j.contains("rate_hz")) throw ConfigError(path + ": capture header has no rate_hz (the samples' rate, Hz)");
    if (!j["rate_hz"].is_number())
      throw ConfigError(path + ": capture header field rate_hz is " + j["rate_hz"].dump() + ", not a number");
    header_.rate_hz = j["rate_hz"].get<double>();
    header_.extra = j.value("extra", nlohmann::json::object());
    // A capture whose header names its stream's y (rig capture import of a stream with y): a
    // NaN y there is a non-finite value like any other, not a stream without y (a review).
    if (const auto sj = header_.extra.find("stream"); sj != header_.extra.end() && sj->is_object())
      if (const auto y = sj->find("y"); y != sj->end() && y->is_string() && !y->get<std::string>().empty())
        y_named_ = true;
  } catch (const RepeatedJsonKey& e) {
    throw ConfigError(path + ": capture header: " + e.what());
  } catch (const nlohmann::json::exception& e) {
    throw ConfigError(path + ": capture header is not valid JSON: " + e.what());
  }
  // A rate the analysis cannot use is named here, not later as an option error or a PSD failure.
  if (!std::isfinite(header_.rate_hz) || header_.rate_hz < kMinRateHz || header_.rate_hz > kMaxRateHz) {
    std::ostringstream os;
    os << path << ": capture header rate_hz = " << header_.rate_hz << " is out of range [" << kMinRateHz << ", "
       << kMaxRateHz << "] Hz";
    throw ConfigError(os.str());
  }
  data_start_ = align16(16 + len);
  pos_ = data_start_;
  guard.armed = false;
}

Reader::~Reader() {
  if (f_) std::fclose(f_);
}

// Looks for the next valid block header at 16-byte steps after damage.
bool Reader::resync(uint64_t from) {
  unsigned char h[kBlockHeaderSize];
  for (uint64_t p = from; p + kBlockHeaderSize <= file_size_; p += 16) {
    if (std::fseek(f_, static_cast<long>(p), SEEK_SET) != 0) return false;
    if (std::fread(h, 1, kBlockHeaderSize, f_) != kBlockHeaderSize) return false;
    const uint32_t m = get_u32(h);
    if ((m == kBlockMagic || m == kEndMagic) && crc(h, 12) == get_u32(h + 12)) {
      pos_ = p;
      return true;
    }
  }
  return false;
}

bool Reader::next_block() {
  unsigned char h[kBlockHeaderSize];
  for (;;) {
    if (std::fseek(f_, static_cast<long>(pos_), SEEK_SET) != 0) return false;
    const std::size_t got = std::fread(h, 1, kBlockHeaderSize, f_);
    if (got < kBlockHeaderSize) {
      rec_.truncated = true;
      rec_.problem = got == 0 ? "file ends without the end marker (writer did not close it: killed or disk full)"
                              : "file ends inside a block header at offset " + std::to_string(pos_);
      return false;
    }
    const uint32_t magic = get_u32(h);
    const bool hdr_ok = crc(h, 12) == get_u32(h + 12);
    if (hdr_ok && magic == kEndMagic) {
      const uint64_t n = get_u32(h + 4) | (uint64_t{get_u32(h + 8)} << 32);
      const uint64_t after = file_size_ - (pos_ + kBlockHeaderSize);
      if (after > 0) {  // nothing follows a closed capture: say what does and ignore it
        rec_.notes.push_back("offset " + std::to_string(pos_ + kBlockHeaderSize) + ": " + std::to_string(after) +
                             " bytes after the end marker (ignored)");
        if (rec_.problem.empty()) rec_.problem = rec_.notes.back();
      }
      // Complete describes the file: every note but the non-finite values' (the file is whole,
      // its values are not; Recovery::non_finite says so) is damage to the file itself.
      const std::size_t value_notes = std::min<uint64_t>(rec_.non_finite, Recovery::kMaxNonFiniteNotes);
      if (n == rec_.samples && rec_.damaged_blocks == 0 && rec_.notes.size() == value_notes) {
        rec_.complete = true;
      } else if (rec_.problem.empty()) {
        rec_.problem = "end marker counts " + std::to_string(n) + " samples, " + std::to_string(rec_.samples) +
                       " were readable";
      }
      return false;
    }
    const uint32_t count = get_u32(h + 4);
    if (hdr_ok && magic == kBlockMagic && count > 0 && count <= kMaxBlockSamples) {
      const uint64_t payload = uint64_t{count} * kRecordSize;
      if (pos_ + kBlockHeaderSize + payload > file_size_) {
        rec_.truncated = true;
        rec_.problem = "last block at offset " + std::to_string(pos_) + " is incomplete (" +
                       std::to_string(file_size_ - pos_ - kBlockHeaderSize) + " of " + std::to_string(payload) +
                       " payload bytes): writer killed mid-block";
        return false;
      }
      block_.resize(count);
      if (std::fread(block_.data(), 1, payload, f_) != payload) return false;
      if (crc(block_.data(), payload) == get_u32(h + 8)) {
        if (rec_.blocks > 0 && count == prev_count_ && get_u32(h + 8) == prev_crc_) {
          // The same block twice (its sequence numbers are in the payload): counted once, noted.
          rec_.notes.push_back("offset " + std::to_string(pos_) + ": block of " + std::to_string(count) +
                               " samples repeats the previous block (skipped)");
          if (rec_.problem.empty()) rec_.problem = rec_.notes.back();
          pos_ += kBlockHeaderSize + payload;
          continue;
        }
        prev_count_ = count;
        prev_crc_ = get_u32(h + 8);
        flag_non_finite(pos_);
        pos_ += kBlockHeaderSize + payload;
        block_pos_ = 0;
        ++rec_.blocks;
        rec_.samples += count;
        if (gap_pending_) {
          block_[0].status |= sample_status::kGapBefore;
          gap_pending_ = false;
        }
        return true;
      }
      ++rec_.damaged_blocks;
      rec_.notes.push_back("offset " + std::to_string(pos_) + ": block of " + std::to_string(count) +
                           " samples fails its payload CRC (skipped)");
      if (rec_.problem.empty()) rec_.problem = rec_.notes.back();
      gap_pending_ = true;
      pos_ += kBlockHeaderSize + payload;
      continue;
    }
    // Unreadable block header: scan forward for the next valid one.
    ++rec_.damaged_blocks;
    rec_.notes.push_back("offset " + std::to_string(pos_) + ": damaged block header");
    if (rec_.problem.empty()) rec_.problem = rec_.notes.back();
    gap_pending_ = true;
    if (!resync(pos_ + 16)) {
      rec_.truncated = true;
      return false;
    }
  }
}

// A valid CRC only says the bytes are as written: the values may still be NaN or inf.
void Reader::flag_non_finite(uint64_t block_pos) {
  for (std::size_t i = 0; i < block_.size(); ++i) {
    const Sample& s = block_[i];
    if (std::isfinite(s.x_g) && std::isfinite(s.y_g)) continue;
    const uint64_t offset = block_pos + kBlockHeaderSize + i * kRecordSize;
    if (!y_named_ && std::isfinite(s.x_g) && std::isnan(s.y_g)) {  // no y: a stream without it (not damage)
      if (rec_.y_absent++ == 0)
        rec_.first_y_absent = "offset " + std::to_string(offset) + ": sample " + std::to_string(rec_.samples + i);
      continue;
    }
    if (rec_.non_finite++ < Recovery::kMaxNonFiniteNotes) {
      rec_.notes.push_back("offset " + std::to_string(offset) + ": sample " + std::to_string(rec_.samples + i) +
                           " has x = " + std::to_string(s.x_g) + ", y = " + std::to_string(s.y_g) +
                           " (not a finite number)");
      if (rec_.problem.empty()) rec_.problem = rec_.notes.back();
    }
  }
}

std::size_t Reader::read(std::span<Sample> out) {
  std::size_t n = 0;
  while (n < out.size()) {
    if (block_pos_ >= block_.size()) {
      if (done_ || !next_block()) {
        done_ = true;
        block_.clear();
        block_pos_ = 0;
        break;
      }
    }
    const std::size_t k = std::min(out.size() - n, block_.size() - block_pos_);
    std::memcpy(out.data() + n, block_.data() + block_pos_, k * sizeof(Sample));
    n += k;
    block_pos_ += k;
  }
  return n;
}

Loaded load(const std::string& path) {
  Reader r(path);
  Loaded l;
  l.header = r.header();
  // Room for every sample the file can hold, reserved once: the vector's doubling had copied a
  // 60 min capture's 58 MB about twice over, into fresh pages each time (half of the `paper`
  // procedure's page faults), and huge pages under it take 512 faults in one. A file larger
  // than memory can hold (mostly junk: only its valid blocks are read) grows as it is read.
  bool reserved = true;
  try {
    l.samples.reserve(static_cast<std::size_t>(r.max_samples()));
    advise_huge_pages(l.samples.data(), l.samples.capacity() * sizeof(Sample));
  } catch (const std::bad_alloc&) {
    reserved = false;
  }
  // Straight into the result, in chunks growing from 256 samples to 64 Ki: no fixed 64 Ki
  // bounce buffer, whose zero-filling (1 MiB) cost more than reading a small file
  // (tests/fuzz/fuzz_capture.cpp spent 57 % of its time there). A reserved vector never moves:
  // no chunk goes past the reservation.
  for (std::size_t chunk = 256;; chunk = std::min<std::size_t>(chunk * 2, 1 << 16)) {
    const std::size_t have = l.samples.size();
    const std::size_t want = reserved ? std::min(chunk, l.samples.capacity() - have) : chunk;
    if (want == 0) break;
    l.samples.resize(have + want);
    const std::size_t n = r.read(std::span<Sample>(l.samples).subspan(have));
    l.samples.resize(have + n);
    if (n < want) break;
  }
  // The reader's account (end marker, damage) is complete once a read returns 0: after a full
  // reservation (a file of a header alone, whose room is 0) it has not said so yet.
  for (Sample s; r.read(std::span<Sample>(&s, 1)) == 1;) l.samples.push_back(s);
  l.recovery = r.recovery();
  return l;
}

namespace {
template <class Field>
std::vector<double> channel(std::span<const Sample> s, Field f) {
  std::vector<double> v;
  v.reserve(s.size());
  advise_huge_pages(v.data(), s.size() * sizeof(double));
  v.resize(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) v[i] = f(s[i]);
  return v;
}
}  // namespace

std::vector<double> channel_x(std::span<const Sample> s) {
  return channel(s, [](const Sample& x) { return double{x.x_g}; });
}
std::vector<double> channel_y(std::span<const Sample> s) {
  return channel(s, [](const Sample& x) { return double{x.y_g}; });
}

std::optional<uint32_t> lost_between(uint32_t prev, uint32_t seq) {
  const uint32_t step = seq - prev;  // modulo 2^32
  if (step == 0 || step >= (1u << 31)) return std::nullopt;
  return step - 1u;
}

}  // namespace rig::capture
