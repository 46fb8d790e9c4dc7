#include "rig/gpio/gpiod_lines.hpp"

#include <poll.h>

#include <cerrno>
#include <chrono>
#include <iterator>
#include <optional>
#include <system_error>
#include <utility>

#include <gpiod.hpp>

#include "rig/core/errors.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/core/wake_fd.hpp"

namespace rig::gpio {

namespace {

class GpiodLines final : public LineDriver {
 public:
  explicit GpiodLines(const GpioConfig& cfg) : cfg_(cfg) {
    if (!cfg.chip.empty()) {
      try {
        chip_ = gpiod::chip(cfg.chip);  // by name, path, label or number
      } catch (const std::exception& e) {
        throw HardwareError("[gpio] chip = \"" + cfg.chip + "\": cannot open GPIO chip: " + e.what());
      }
    }
    auto out_flags = [](bool active_low) { return active_low ? gpiod::line_request::FLAG_ACTIVE_LOW : std::bitset<32>{}; };
    out_[0] = request("power", cfg.power, gpiod::line_request::DIRECTION_OUTPUT, out_flags(cfg.power_active_low));
    const std::string* lamps[4] = {&cfg.lamp_ready, &cfg.lamp_running, &cfg.lamp_pass, &cfg.lamp_fail};
    const char* keys[4] = {"lamp_ready", "lamp_running", "lamp_pass", "lamp_fail"};
    for (int i = 0; i < 4; ++i)
      if (!lamps[i]->empty())
        out_[i + 1] = request(keys[i], *lamps[i], gpiod::line_request::DIRECTION_OUTPUT, {});
    estop_ = request("estop", cfg.estop, gpiod::line_request::EVENT_BOTH_EDGES,
                     cfg.estop_active_low ? gpiod::line_request::FLAG_ACTIVE_LOW : std::bitset<32>{});
  }

  bool has(Output o) const override { return static_cast<bool>(out_[static_cast<int>(o)]); }

  void set(Output o, bool active) override {
    auto& l = out_[static_cast<int>(o)];
    if (!l) return;
    try {
      l.set_value(active ? 1 : 0);
    } catch (const std::exception& e) {
      throw HardwareError("GPIO line " + l.name() + ": set_value: " + e.what());
    }
  }

  bool estop_active() override {
    try {
      return estop_.get_value() != 0;
    } catch (const std::exception& e) {
      throw HardwareError("GPIO e-stop line " + cfg_.estop + ": get_value: " + e.what());
    }
  }

  GpiodLines(const GpiodLines&) = delete;
  GpiodLines& operator=(const GpiodLines&) = delete;

  std::optional<bool> wait_estop_edge(std::chrono::milliseconds timeout) override {
    // poll on the line's event descriptor and the wake eventfd (libgpiod's event_wait polls the
    // line alone, so a leaving rig waited out the timeout).
    pollfd fds[2] = {{estop_.event_get_fd(), POLLIN, 0}, {wake_.get(), POLLIN, 0}};
    const int r = poll(fds, wake_.get() >= 0 ? 2 : 1, static_cast<int>(timeout.count()));
    if (r < 0) {
      if (errno == EINTR) return std::nullopt;
      throw HardwareError("GPIO e-stop line " + cfg_.estop + ": poll: " + std::system_category().message(errno));
    }
    // A chip that went away (an unplugged expander, a removed gpio-sim) reports an error or a
    // hang-up without data, at once, on every poll: the line can no longer be read, which the
    // watcher takes as a pressed e-stop (a code review: it spun here, the DUT still powered).
    if ((fds[0].revents & (POLLERR | POLLHUP | POLLNVAL)) != 0 && (fds[0].revents & POLLIN) == 0)
      throw HardwareError("GPIO e-stop line " + cfg_.estop + ": the line's chip reports an error or is gone");
    if (r == 0 || (fds[0].revents & POLLIN) == 0) return std::nullopt;  // timeout, or woken
    // Edges are reported in logical (active-low corrected) terms.
    const gpiod::line_event ev = estop_.event_read();
    // The uAPI v1 stamps line events with CLOCK_MONOTONIC (Linux >= 5.7), the
    // clock steady_clock reads on Linux.
    last_edge_ = std::chrono::steady_clock::time_point(
        std::chrono::duration_cast<std::chrono::steady_clock::duration>(ev.timestamp));
    return ev.event_type == gpiod::line_event::RISING_EDGE;
  }

  std::optional<std::chrono::steady_clock::time_point> last_edge_time() const override { return last_edge_; }

  void wake() override { wake_.wake(); }

  std::string describe() const override {
    std::string s = "libgpiod lines";
    if (chip_) s += " on " + chip_.name() + " (" + chip_.label() + ")";
    s += ": power=" + cfg_.power + ", estop=" + cfg_.estop;
    return s;
  }

 private:
  gpiod::line request(const char* key, const std::string& name, int type, std::bitset<32> flags) {
    gpiod::line l;
    try {
      l = chip_ ? chip_.find_line(name) : gpiod::find_line(name);
    } catch (const std::exception& e) {
      throw HardwareError(std::string("[gpio] ") + key + " = \"" + name + "\": looking up the line: " + e.what());
    }
    if (!l)
      throw HardwareError(std::string("[gpio] ") + key + " = \"" + name + "\": no GPIO line of that name" +
                          (chip_ ? " on " + chip_.name() : std::string(" on any chip")));
    try {
      l.request({cfg_.consumer, type, flags}, 0);
    } catch (const std::exception& e) {
      throw HardwareError(std::string("[gpio] ") + key + " = \"" + name + "\": request failed (line busy?): " + e.what());
    }
    return l;
  }

  GpioConfig cfg_;
  gpiod::chip chip_;
  gpiod::line out_[kOutputs];
  gpiod::line estop_;
  WakeFd wake_;  // written by wake(); a member, so a constructor that throws does not leak it
  std::optional<std::chrono::steady_clock::time_point> last_edge_;
};

}  // namespace

GpioConfig parse_gpio_config(const toml::table& t) {
  cfg::check_keys(t, {"chip", "power", "estop", "lamp_ready", "lamp_running", "lamp_pass", "lamp_fail",
                      "power_active_low", "estop_active_low", "consumer"},
                  "gpio");
  GpioConfig c;
  c.chip = cfg::get_string(t, "chip", "");
  c.power = cfg::get_string(t, "power");
  c.estop = cfg::get_string(t, "estop");
  c.lamp_ready = cfg::get_string(t, "lamp_ready", "");
  c.lamp_running = cfg::get_string(t, "lamp_running", "");
  c.lamp_pass = cfg::get_string(t, "lamp_pass", "");
  c.lamp_fail = cfg::get_string(t, "lamp_fail", "");
  c.power_active_low = cfg::get_bool(t, "power_active_low", false);
  c.estop_active_low = cfg::get_bool(t, "estop_active_low", true);
  c.consumer = cfg::get_string(t, "consumer", "rig");
  for (const char* key : {"power", "estop"})
    if (cfg::get_string(t, key).empty()) throw ConfigError(cfg::where(*t.get(key)) + ": [gpio] " + key + " is empty");
  // One line, one job: a lamp on the e-stop input would drive the safety line, and a line named
  // twice is refused by libgpiod only once the chip is open.
  const std::pair<const char*, const std::string*> lines[] = {
      {"power", &c.power},         {"estop", &c.estop},         {"lamp_ready", &c.lamp_ready},
      {"lamp_running", &c.lamp_running}, {"lamp_pass", &c.lamp_pass}, {"lamp_fail", &c.lamp_fail}};
  for (std::size_t j = 1; j < std::size(lines); ++j)
    for (std::size_t i = 0; i < j; ++i)
      if (!lines[j].second->empty() && *lines[j].second == *lines[i].second)
        throw ConfigError(cfg::where(*t.get(lines[j].first)) + ": [gpio] " + lines[j].first +
                          " names the same line as " + lines[i].first + " ('" + *lines[j].second + "')");
  return c;
}

std::unique_ptr<LineDriver> open_gpiod_lines(const GpioConfig& cfg) { return std::make_unique<GpiodLines>(cfg); }

std::unique_ptr<RigIo> connect_gpio(const toml::table& gpio_cfg) {
  return std::make_unique<LineRigIo>(open_gpiod_lines(parse_gpio_config(gpio_cfg)));
}

}  // namespace rig::gpio
