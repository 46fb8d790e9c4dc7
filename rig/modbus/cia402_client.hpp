// The rig's CiA 402 table backend: positions a dividing head driven by a CiA
// 402 servo drive (IEC 61800-7-201) whose objects sit on Modbus registers as a
// drive map says (rig/modbus/drive_map.hpp). State machine to Operation
// enabled, homing mode, profile position mode with the set-point handshake,
// halt and quick stop; every wait reads statusword, modes display, position
// and velocity actual; every call is bounded in time.
#pragma once
#include <atomic>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rig/core/clock.hpp"
#include "rig/core/table.hpp"
#include "rig/modbus/cia402.hpp"
#include "rig/modbus/drive_map.hpp"
#include "rig/modbus/stop_latch.hpp"
#include "rig/modbus/table_client.hpp"
#include "rig/modbus/transport.hpp"

namespace rig::modbus {

// What one poll reads.
struct Cia402Reading {
  uint16_t statusword = 0, error_code = 0;
  int mode_display = 0;
  double actual_deg = 0, velocity_dps = 0;
  // Read while a move waits (read(cancel, true)): what another master may have written.
  std::optional<uint16_t> controlword;
  std::optional<int64_t> target_counts;
  cia402::State state() const { return cia402::decode_state(statusword); }
  bool has(uint16_t bit) const { return (statusword & bit) != 0; }
};

class Cia402Table final : public RotaryTable {
 public:
  Cia402Table(std::unique_ptr<RegisterTransport> transport, DriveMap map, Clock& clock, TableOptions opt = {});

  TableStatus status() override;
  void home(const CancelToken& cancel) override;
  void move_to(double deg, const CancelToken& cancel) override;
  void stop() noexcept override;        // halt (controlword bit 8) on the profile deceleration
  void quick_stop() noexcept override;  // Quick stop command (transition 11)
  std::string describe() const override;
  // The drive map's [limits] (the drive's own 0x607D should match them).
  std::optional<std::pair<double, double>> travel_deg(const CancelToken&) override {
    return std::pair{map_.limit_neg_deg, map_.limit_pos_deg};
  }
  std::string stop_fate() const override { return last_stop_error(); }

  // Technician's fault reset (`rig table reset`): returns the 0x603F code it
  // cleared (0: no fault); HardwareError naming the code when the drive stays in Fault.
  uint16_t reset_fault(const CancelToken& cancel);
  // `commands`: also the controlword and target position, as the drive holds them.
  Cia402Reading read(const CancelToken& cancel = {}, bool commands = false);
  std::string last_stop_error() const {
    std::lock_guard lk(stop_mu_);
    return last_stop_error_;
  }
  // The last stop was not sent because none was needed (the power stage off); last_stop_error
  // says so ("no halt needed: ...").
  bool last_stop_needless() const {
    std::lock_guard lk(stop_mu_);
    return stop_needless_;
  }
  const DriveMap& map() const { return map_; }

 private:
  int64_t read_object(Obj o, const CancelToken& cancel, bool urgent = false);
  void write_object(Obj o, int64_t value, const CancelToken& cancel, bool urgent = false);
  void write_controlword(uint16_t w, const CancelToken& cancel);
  void enable_operation(const std::string& doing, const CancelToken& cancel);
  void set_mode(const std::string& doing, int mode, const CancelToken& cancel);
  void wait_at_rest(const std::string& doing, const CancelToken& cancel);
  Cia402Reading await_state(const std::string& doing, const char* command, cia402::State want,
                            const CancelToken& cancel);
  // `after` ends the message: "; nothing sent" where the check comes before any write.
  void fail_on_fault(const std::string& doing, const Cia402Reading& r, const char* after = "") const;
  std::string at(const Cia402Reading& r) const;
  void identify(const Cia402Reading& r, const CancelToken& cancel);
  // `is_402`, when given, is set where the device is a CiA 402 drive whatever the problem (its
  // device type's 0x0192 in the other word: the map's word order reversed).
  std::string identity_problem(uint16_t statusword, const CancelToken& cancel, bool urgent, bool* is_402 = nullptr);
  void fail_unless_moving(const std::string& doing, const Cia402Reading& r, const char* when,
                          int64_t target_counts) const;
  void fail_on_halt(const std::string& doing, const Cia402Reading& r, const char* when) const;
  void fail_unless_mode(const std::string& doing, const Cia402Reading& r, const char* when, int8_t mode) const;
  static bool drive_restarted(const Cia402Reading& r);
  void send_stop(uint16_t word, const char* name) noexcept;
  bool stop_goes_out(uint16_t statusword, const char* name) noexcept;
  bool axis_reads_at_rest() noexcept;
  // HardwareError when a homed table's position actual reads outside the map's travel.
  void refuse_outside_travel(const std::string& doing, const Cia402Reading& r) const;
  // HardwareError when a home the drive reports attained does not read as one through the map.
  void refuse_misread_home(const std::string& doing, const Cia402Reading& r) const;
  // Whether reading `r` is a servo holding position; `prev`: the reading a poll before, if any.
  bool reads_at_rest(const Cia402Reading& r, const Cia402Reading* prev) const;
  template <class Body>
  void guarded(const std::string& doing, Body body);

  std::unique_ptr<RegisterTransport> transport_;
  DriveMap map_;
  Clock& clock_;
  TableOptions opt_;
  std::atomic<uint16_t> control_{0};
  std::atomic<bool> control_known_{false};  // control_ was read from or written to the drive
  std::atomic<bool> control_written_{false};  // control_ is a word this client wrote (the halt's fallback)
  std::atomic<bool> identified_{false};       // a reading showed a CiA 402 drive (identify)
  bool homed_ = false;            // homed by this client (when the map names no homed bit)
  bool profile_applied_ = false;
  // A stop that did not go out, said as its parts joined (noexcept: the safe-state path).
  void stop_not_sent(std::initializer_list<std::string_view> said) noexcept;
  mutable std::mutex stop_mu_;
  std::string last_stop_error_;
  bool stop_needless_ = false;
  detail::StopLatch stops_;  // a stop asked while a move or homing runs: none of its words over it
};

}  // namespace rig::modbus
