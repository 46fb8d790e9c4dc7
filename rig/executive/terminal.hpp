// The terminal view of a run: the phase list, a progress bar with ETA in
// device time and wall time, and log lines. On a TTY the bar redraws in place;
// otherwise (CI logs) it prints a line per phase and per quarter.
#pragma once
#include <fmt/format.h>
#include <cstdio>
#include <string>
#include <vector>

#include "rig/executive/executive.hpp"

namespace rig {

class TerminalView final : public ProgressSink {
 public:
  explicit TerminalView(std::FILE* out, bool quiet = false);
  // `kept`: the first phases a resume keeps from its checkpoint (the line says what is left).
  void plan(const std::vector<Phase>& phases, std::size_t kept = 0);
  void phase_started(std::size_t index, std::size_t count, const std::string& id, const std::string& title,
                     double planned_s) override;
  void phase_progress(double fraction, double sim_now_s) override;
  void phase_finished(const std::string& id, const std::string& status, const std::string& message) override;
  void log(const std::string& line) override;

  static std::string hms(double s);

 private:
  template <class... Args>
  void put(fmt::format_string<Args...> f, Args&&... args);
  void draw(bool final_line);
  std::FILE* out_;
  bool tty_, quiet_;
  std::vector<double> planned_;
  std::vector<std::string> ids_;
  std::size_t index_ = 0, count_ = 0;
  double fraction_ = 0, last_draw_wall_ = -1, wall_start_ = 0, done_planned_ = 0, done_at_start_ = 0;
  bool running_ = false;  // a phase of this session has started
  int last_quarter_ = -1;
};

}  // namespace rig
