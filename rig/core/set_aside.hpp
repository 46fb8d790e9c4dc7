// Keeping what an interrupted attempt left: before a recording writes its file again, the file
// already there is renamed PATH.interrupted-N (the first free N), kept as it was and never read.
// A resume repeats a recording whose phase the checkpoint does not hold; its earlier file is
// evidence of what the rig did to the DUT, so it is never overwritten.
#pragma once
#include <filesystem>
#include <string>

namespace rig {

// Renames an existing `path` to path.interrupted-N; returns the new name, or "" when nothing was
// there. Throws std::filesystem::filesystem_error when the rename fails.
inline std::string set_aside(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(path, ec))) return {};
  for (int i = 1;; ++i) {
    const std::string keep = path + ".interrupted-" + std::to_string(i);
    if (!fs::exists(fs::symlink_status(keep, ec))) {
      fs::rename(path, keep);
      return keep;
    }
  }
}

}  // namespace rig
