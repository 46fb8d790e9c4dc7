// What a file was when its writer closed it (size, modification time, inode), to tell at the end
// of a run whether a record is still the one written: a capture truncated or rewritten by
// anything else while the run went on (a clean-up script, a hand, a full disk's repair) keeps its
// name, and a verdict on it would stand on samples the folder no longer holds (a review).
#pragma once
#include <sys/stat.h>

#include <cstdint>
#include <optional>
#include <string>

#include <fmt/format.h>

namespace rig {

struct FileStamp {
  std::uint64_t size = 0, inode = 0, device = 0;
  std::int64_t mtime_ns = 0;
  bool operator==(const FileStamp&) const = default;
};

// The file's stamp now; nothing when it cannot be read (gone, not a file).
inline std::optional<FileStamp> stamp_of(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return std::nullopt;
  return FileStamp{static_cast<std::uint64_t>(st.st_size), static_cast<std::uint64_t>(st.st_ino),
                   static_cast<std::uint64_t>(st.st_dev),
                   static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1'000'000'000 + st.st_mtim.tv_nsec};
}

// How `now` differs from `then`, for a message ("" when it does not).
inline std::string stamp_change(const FileStamp& then, const FileStamp& now) {
  if (now.inode != then.inode || now.device != then.device) return "replaced by another file";
  if (now.size != then.size) return fmt::format("{} bytes when written, {} now", then.size, now.size);
  if (now.mtime_ns != then.mtime_ns) return "written to after its writer closed it";
  return {};
}

}  // namespace rig
