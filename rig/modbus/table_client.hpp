// The rig's rotary-table client: positions a dividing head through the register
// map in docs/table-registers.md over any RegisterTransport (libmodbus TCP/RTU
// on hardware, in-process in the emulated plant), so one piece of logic is
// exercised in both.
#pragma once
#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include <toml++/toml.h>

#include "rig/core/clock.hpp"
#include "rig/core/table.hpp"
#include "rig/modbus/drive_map.hpp"
#include "rig/modbus/stop_latch.hpp"
#include "rig/modbus/transport.hpp"

namespace rig::modbus {

struct TableOptions {
  double tolerance_deg = 0.01;     // |actual - commanded| accepted after the settle time
  double settle_s = table_defaults::kClientSettleS;  // in position held continuously this long (client side)
  double poll_s = table_defaults::kClientPollS;      // status polling period while waiting
  double move_timeout_s = 0.0;     // 0 = from the drive's profile: 2 x trapezoid time + settle + 10 s
  double home_timeout_s = 180.0;
  double ack_timeout_s = 1.0;      // a start/home command must be acknowledged within this
  double heartbeat_timeout_s = 2.0;// drive heartbeat frozen this long = controller hung
  // A run read as ended short of its goal this long is one: a homing run at rest, not homed, no
  // longer homing; a rig-v1 move in position at a stop point off its target. A drive may set its
  // end-of-run bits some cycles apart (a review: 15 ms between CiA 402's bits 10 and 12, read at
  // poll_s = 0.005, failed a good run); a homing method that dwells at a switch longer needs more.
  double ended_short_s = 1.0;
  // CiA 402: the table moving this long without the set-point acknowledge after the word that
  // released halt is halted (a drive continuing a halted move). A drive may set bit 12 some cycles
  // after its motion starts; one that sets it later needs more.
  double unacked_motion_s = 0.1;
  // Written to the drive before the first motion when set (else the drive's own).
  std::optional<double> velocity_dps, accel_dps2, in_position_window_deg, drive_settle_s;
  // Where each of those four was written ("rig.toml:7:1"), for the message if the drive refuses it.
  std::map<std::string, std::string, std::less<>> written_at;
  std::string where(std::string_view key) const {
    const auto it = written_at.find(key);
    return it == written_at.end() ? std::string() : it->second;
  }
};

// Decoded drive registers [0, reg::kBlockEnd).
struct DriveState {
  uint16_t control = 0, status = 0, alarm_code = 0, move_seq = 0;
  uint32_t heartbeat = 0;
  double actual_deg = 0, target_deg = 0, velocity_dps = 0, accel_dps2 = 0;
  double window_deg = 0, settle_s = 0, actual_vel_dps = 0, following_err_deg = 0;
  double limit_neg_deg = 0, limit_pos_deg = 0;
  bool has(uint16_t status_bit) const { return (status & status_bit) != 0; }
};
DriveState decode_drive_state(const std::vector<uint16_t>& regs);
TableStatus to_table_status(const DriveState& d);

class TableClient final : public RotaryTable {
 public:
  TableClient(std::unique_ptr<RegisterTransport> transport, Clock& clock, TableOptions opt = {});

  TableStatus status() override;
  void home(const CancelToken& cancel) override;
  void move_to(double deg, const CancelToken& cancel) override;
  void stop() noexcept override;
  void quick_stop() noexcept override;
  std::string describe() const override;
  // The drive's LIMIT_NEG / LIMIT_POS registers (docs/table-registers.md).
  std::optional<std::pair<double, double>> travel_deg(const CancelToken& cancel) override;
  std::string stop_fate() const override { return last_stop_error(); }

  // Technician's alarm reset (`rig table reset`): refused while the e-stop is
  // pressed or the interlock is open; throws HardwareError when the alarm stays.
  void reset_alarm(const CancelToken& cancel);
  DriveState read_drive(const CancelToken& cancel = {});
  // Why the last stop()/quick_stop() could not be delivered ("" when it was).
  std::string last_stop_error() const {
    std::lock_guard lk(stop_mu_);
    return last_stop_error_;
  }
  // The last stop's servo bit was a guess: the drive's state could not be read before it (a link
  // that did not answer in time), so the stop went out with SERVO_ON cleared, which a drive that
  // takes it also reads as "servo off" (a stop never enables the servo). "" when it was known.
  std::string last_stop_note() const {
    std::lock_guard lk(stop_mu_);
    return last_stop_note_;
  }
  RegisterTransport& transport() { return *transport_; }

 private:
  void write_control(uint16_t word, const CancelToken& cancel);
  void set_stop_note(std::string note) noexcept;
  void prepare_motion(const std::string& doing, const CancelToken& cancel);
  DriveState wait_at_rest(const std::string& doing, DriveState d, const CancelToken& cancel);
  void apply_profile_once(const CancelToken& cancel);
  void fail_on_alarm(const std::string& doing, const DriveState& d);
  void fail_on_stop_bits(const std::string& doing, const DriveState& d) const;
  void fail_on_servo_off(const std::string& doing, const DriveState& d) const;
  void watch_heartbeat(const std::string& doing, const DriveState& d, double& last_change_s, uint32_t& last_hb);
  void send_stop(uint16_t bit, const char* name) noexcept;
  bool refuse_stop_to_unknown(const char* name) noexcept;
  std::string at(const DriveState& d) const;
  template <class Body>
  void guarded(const std::string& doing, Body body);

  std::unique_ptr<RegisterTransport> transport_;
  Clock& clock_;
  TableOptions opt_;
  // Last control word read or written; stop() may run on another thread while a move polls.
  std::atomic<uint16_t> control_{0};
  detail::StopLatch stops_;  // the stops asked of this client since the move or homing began
  std::atomic<bool> identified_{false};  // a status block read with MAP_VERSION 1
  bool profile_applied_ = false;
  double last_actual_deg_ = 0;     // for messages when the link is lost
  bool have_actual_ = false;
  mutable std::mutex stop_mu_;
  std::string last_stop_note_;  // under stop_mu_
  std::string last_stop_error_;
};

// Options from a [table] TOML table (hardware file); rejects unknown keys with
// file:line. Keys: see docs/table-registers.md.
TableOptions table_options_from_toml(const toml::table& t);
LinkOptions link_options_from_toml(const toml::table& t);

// [table] drive = "rig-v1" (default) | "cia402"; checks drive/drive_map consistency.
std::string table_drive(const toml::table& table_cfg);
// The [table] drive_map file (relative paths: beside the file naming it, else the working folder).
DriveMap table_drive_map(const toml::table& table_cfg);

// Checks every [table] key, the drive map included, without connecting
// (ConfigError naming file:line), so a hardware file is refused before any device opens.
void check_table_config(const toml::table& table_cfg);

// The drive a [table] section names, as one line: a TCP endpoint and unit ("tcp:10.0.0.7:502 unit
// 1", the host as the least IPv4 address as text it resolves to, so "localhost" and "127.0.0.1" are one
// key; a name that does not resolve as written, in lower case), or a serial device, resolved
// ("rtu:/dev/ttyUSB0", whatever the line settings and unit); what a station's table lock is keyed
// on. A host name is looked up (getaddrinfo) each call: a stop computes it after it is sent.
std::string table_identity(const toml::table& table_cfg);

// Hardware: connects to the drive named by [table] `modbus = "tcp:HOST:PORT"` or
// `rtu = "/dev/ttyUSB0,115200,N,8,1"`. Throws ConfigError / HardwareError.
std::unique_ptr<RotaryTable> connect_table(const toml::table& table_cfg, Clock& clock);
// A client over a register device in this process (the emulated drive).
std::unique_ptr<RotaryTable> make_inprocess_table(RegisterDevice& dev, Clock& clock, TableOptions opt = {});

}  // namespace rig::modbus
