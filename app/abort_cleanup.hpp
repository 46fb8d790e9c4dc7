// A file a subcommand is writing when a signal ends it: the subcommands without a SignalWatcher of
// their own (analyze, filter, capture import, ...) end in main.cpp's handler, which _exits at
// once, and a half-written staged file stayed behind (a technician's review). The handler unlinks
// the one file named here (unlink is async-signal-safe) and prints its note.
#pragma once
#include <atomic>
#include <cstring>
#include <string>

namespace rig::cli {

struct AbortCleanup {
  char path[4096];
  char note[4096];
};

// The slot the handler reads; null when nothing is staged.
inline std::atomic<const AbortCleanup*> g_abort_cleanup{nullptr};

// Names `path` (and what to say on stderr when it goes) until the returned guard ends. One at a
// time: the outputs are written one after another. A path too long for the slot is not named.
class RemoveOnAbort {
 public:
  RemoveOnAbort(const std::string& path, const std::string& note) {
    if (path.size() >= sizeof(slot_.path) || note.size() >= sizeof(slot_.note)) return;
    std::memcpy(slot_.path, path.c_str(), path.size() + 1);
    std::memcpy(slot_.note, note.c_str(), note.size() + 1);
    g_abort_cleanup.store(&slot_);
  }
  ~RemoveOnAbort() { release(); }
  RemoveOnAbort(const RemoveOnAbort&) = delete;
  RemoveOnAbort& operator=(const RemoveOnAbort&) = delete;
  // The file is settled (renamed into place or removed): a signal now leaves it.
  void release() {
    const AbortCleanup* mine = &slot_;
    g_abort_cleanup.compare_exchange_strong(mine, nullptr);
  }

 private:
  AbortCleanup slot_{};
};

}  // namespace rig::cli
