// One rig process at a time commands a table from this station: an exclusive flock(2) on a lock
// file named after the drive's endpoint and unit, held for the command's or the run's life (the
// kernel drops it however the process ends). Two terminals could home or move one table at once;
// a `rig table move` during a run's recording turned the DUT under it (a review). The drive's own
// "another master" checks still catch other stations and tools. Stops never take the lock.
#pragma once
#include <string>

namespace rig::cli {

class TableLock {
 public:
  // Takes the lock of the drive `identity` names (modbus::table_identity) without waiting;
  // `holder` says who holds it ("rig table move 90", "rig run --out DIR"), shown to a process
  // refused. Throws ConfigError naming the holder's pid and words when another process has it.
  // Where no lock folder can be written the command goes on unlocked, as before there was one.
  TableLock(const std::string& identity, const std::string& holder);
  ~TableLock();
  TableLock(const TableLock&) = delete;
  TableLock& operator=(const TableLock&) = delete;
  bool held() const { return fd_ >= 0; }

  // The lock file for `identity`: in $RIG_LOCK_DIR, else /run/lock, else the temporary folder.
  static std::string path_for(const std::string& identity);

 private:
  int fd_ = -1;
};

}  // namespace rig::cli
