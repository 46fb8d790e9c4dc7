#include "app/station_stop.hpp"

#include <utility>

#include "app/table_lock.hpp"
#include "rig/core/errors.hpp"
#include "rig/modbus/motion_text.hpp"

namespace rig::cli {

void motion_stoppable_from_this_station(const std::string& identity, const std::string& doing,
                                        const std::function<void()>& motion,
                                        const std::function<void(const std::string& by)>& halted) {
  const auto began = std::chrono::system_clock::now();
  try {
    motion();
  } catch (const modbus::detail::TakenOverError&) {
    // The stopping process writes its note once the drive has answered its stop, which this
    // client may read first: up to 1.5 s for it (a loaded machine), on this error path only.
    const auto by = TableLock::stop_noted_since(identity, began, std::chrono::milliseconds(1500));
    if (!by) throw;
    if (halted) halted(*by);
    throw AbortedError("aborted: " + doing + " halted by " + *by + " on this station");
  }
}

StationStoppableTable::StationStoppableTable(std::unique_ptr<RotaryTable> drive, std::string identity)
    : drive_(std::move(drive)), identity_(std::move(identity)) {
  drive_->on_angle([this](double deg) { angle_seen(deg); });
}

void StationStoppableTable::home(const CancelToken& cancel) {
  motion_stoppable_from_this_station(identity_, "homing", [&] { drive_->home(cancel); });
}

void StationStoppableTable::move_to(double deg, const CancelToken& cancel) {
  motion_stoppable_from_this_station(identity_, "moving to " + modbus::detail::deg_str(deg),
                                     [&] { drive_->move_to(deg, cancel); });
}

}  // namespace rig::cli
