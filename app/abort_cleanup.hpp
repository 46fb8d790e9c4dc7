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

// `rig run`'s exit code once its verdict is decided (its passport written), -1 before: a signal
// after that ends the process with this code, never with the abort's (docs/contracts.md).
inline std::atomic<int> g_verdict_exit{-1};

// Names `path` (and what to say on stderr when it goes) until release() or the guard's end. One
// at a time: the outputs are written one after another, and a second guard while one holds the
// slot names nothing. The text lives in two static slots used in turn, never on a stack: the
// handler may run on another thread (a worker of rig analyze) while a guard ends and the next
// begins (a code review).
class RemoveOnAbort {
 public:
  RemoveOnAbort(const std::string& path, const std::string& note) {
    static AbortCleanup slots[2];
    static std::atomic<unsigned> turn{0};
    if (path.size() >= sizeof(AbortCleanup::path) || note.size() >= sizeof(AbortCleanup::note) || g_abort_cleanup.load())
      return;
    AbortCleanup& slot = slots[turn.fetch_add(1) % 2];
    std::memcpy(slot.path, path.c_str(), path.size() + 1);
    std::memcpy(slot.note, note.c_str(), note.size() + 1);
    const AbortCleanup* none = nullptr;
    if (g_abort_cleanup.compare_exchange_strong(none, &slot)) mine_ = &slot;
  }
  ~RemoveOnAbort() { release(); }
  RemoveOnAbort(const RemoveOnAbort&) = delete;
  RemoveOnAbort& operator=(const RemoveOnAbort&) = delete;
  // The file is settled (renamed into place or removed): a signal now leaves it.
  void release() {
    if (const AbortCleanup* m = mine_) g_abort_cleanup.compare_exchange_strong(m, nullptr);
    mine_ = nullptr;
  }

 private:
  const AbortCleanup* mine_ = nullptr;
};

}  // namespace rig::cli
