// A stop sent to the table from this station (`rig table stop` or `quick-stop` in another
// terminal) while a move or homing runs: the operator's abort (exit 3) naming that command, not a
// hardware fault "halted by another master" (exit 4), which is what the drive alone can say (a
// technician's review). The stop leaves a note beside the station's table lock
// (TableLock::note_stop); a halt from another station or tool leaves none and stays a fault.
#pragma once
#include <functional>
#include <memory>
#include <string>

#include "rig/core/table.hpp"

namespace rig::cli {

// Runs `motion` (a home or a move, `doing` naming it: "moving to 90.0000°"); where the drive's
// client finds another master took the axis and a stop from this station was noted since the
// motion began, throws AbortedError("aborted: <doing> halted by `rig table stop` (pid N) on this
// station"); otherwise lets what it threw go on. `halted` is called first with who halted it.
void motion_stoppable_from_this_station(const std::string& identity, const std::string& doing,
                                        const std::function<void()>& motion,
                                        const std::function<void(const std::string& by)>& halted = {});

// A hardware run's table, as the drive's client with that rule on its moves and homing (the run
// ends ABORTED, as Ctrl-C would, rather than ERROR).
class StationStoppableTable final : public RotaryTable {
 public:
  StationStoppableTable(std::unique_ptr<RotaryTable> drive, std::string identity);
  TableStatus status() override { return drive_->status(); }
  void home(const CancelToken& cancel) override;
  void move_to(double deg, const CancelToken& cancel) override;
  void stop() noexcept override { drive_->stop(); }
  void quick_stop() noexcept override { drive_->quick_stop(); }
  std::string describe() const override { return drive_->describe(); }
  std::optional<std::pair<double, double>> travel_deg(const CancelToken& cancel) override {
    return drive_->travel_deg(cancel);
  }
  std::string stop_fate() const override { return drive_->stop_fate(); }

 private:
  std::unique_ptr<RotaryTable> drive_;
  std::string identity_;
};

}  // namespace rig::cli
