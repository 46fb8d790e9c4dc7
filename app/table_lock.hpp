// One rig process at a time commands a table from this station: an exclusive flock(2) on a lock
// file named after the drive (its TCP endpoint and unit, or its serial device), held for the
// command's or the run's life (the kernel drops it however the process ends). Two terminals could
// home or move one table at once; a `rig table move` during a run's recording turned the DUT
// under it (a review). The drive's own "another master" checks still catch other stations and
// tools. Stops never take the lock.
#pragma once
#include <chrono>
#include <optional>
#include <string>

namespace rig::cli {

class TableLock {
 public:
  // Takes the lock of the drive `identity` names (modbus::table_identity) without waiting (a few
  // tries 20 ms apart, as a dry run's check holds it for an instant); `holder` says who holds it
  // ("rig table move 90", "rig run --out DIR"), shown to a process refused. Throws InUseError
  // naming the holder when another process has it, ConfigError when the lock file is not a plain
  // file of its own (a symlink, FIFO, socket or hard link planted in the shared folder). Where
  // the file cannot be opened (no lock folder, no permission) the command goes on unlocked and
  // unlocked_warning() says why: the caller warns.
  TableLock(const std::string& identity, const std::string& holder);
  ~TableLock();
  TableLock(const TableLock&) = delete;
  TableLock& operator=(const TableLock&) = delete;
  bool held() const { return fd_ >= 0; }
  // What the caller warns where the lock could not be taken (held() false, no one else holding it).
  std::string unlocked_warning() const {
    return "the table is not locked against a second rig process on this station: " + unlocked_reason_;
  }

  // For --dry-run, which takes nothing: throws as the constructor would when another process
  // holds the lock now.
  static void check_free(const std::string& identity);

  // The lock file for `identity`: in $RIG_LOCK_DIR, else /run/lock, else the temporary folder.
  static std::string path_for(const std::string& identity);

  // A stop sent from this station leaves a note beside the lock ("pid 4711: rig table stop"), so a
  // move or homing it halts in another terminal ends as the operator's abort (exit 3) naming it,
  // not as "halted by another master" (exit 4: a technician's review). Written after the stop is
  // sent, never before it; never throws: "" when written, else why not (the caller warns: the
  // halted move then says "another master").
  static std::string note_stop(const std::string& identity, const std::string& what);
  // The note of a stop written at or after `since` (this command's start) and within the last
  // 5 s (the halt it made was just seen), never one dated ahead, waiting up to `wait` for it: the
  // stopping process writes it once its stop has been answered, which the halted one may see
  // first. None where no such note comes (another station's or another tool's halt).
  static std::optional<std::string> stop_noted_since(const std::string& identity,
                                                     std::chrono::system_clock::time_point since,
                                                     std::chrono::milliseconds wait);

 private:
  int fd_ = -1;
  std::string unlocked_reason_;
};

}  // namespace rig::cli
