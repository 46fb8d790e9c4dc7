#include "rig/executive/terminal.hpp"

#include <algorithm>
#include <unistd.h>

#include <chrono>

#include <fmt/format.h>

namespace rig {

namespace {
double wall_s() {
  using namespace std::chrono;
  return duration<double>(steady_clock::now().time_since_epoch()).count();
}
}  // namespace

// fmt::print throws when the stream cannot be written (a reader that went away: EPIPE); the
// view is for a person watching, so a write nobody can read is dropped and the run goes on.
template <class... Args>
void TerminalView::put(fmt::format_string<Args...> f, Args&&... args) {
  const std::string text = fmt::format(f, std::forward<Args>(args)...);
  (void)!std::fwrite(text.data(), 1, text.size(), out_);
}

TerminalView::TerminalView(std::FILE* out, bool quiet)
    : out_(out), tty_(::isatty(::fileno(out)) != 0), quiet_(quiet) {}

std::string TerminalView::hms(double s) {
  if (!(s >= 0)) return "--:--:--";
  const long t = static_cast<long>(s + 0.5);
  return fmt::format("{:02d}:{:02d}:{:02d}", t / 3600, (t / 60) % 60, t % 60);
}

void TerminalView::plan(const std::vector<Phase>& phases, std::size_t kept) {
  planned_.clear();
  ids_.clear();
  double total = 0;
  for (const auto& p : phases) {
    planned_.push_back(p.planned_s);
    ids_.push_back(p.id);
    total += p.planned_s;
  }
  if (quiet_) return;
  double left = 0;
  for (std::size_t i = kept; i < phases.size(); ++i) left += phases[i].planned_s;
  // A resume's prompt gives the time left; the plan says both, so the two do not seem to disagree
  // (a technician's review: "Device time 01:44:10", then "Plan: 19 phases, 01:53:50").
  if (kept > 0 && kept <= phases.size())
    put("Plan: {} phases, {} of device time; {} complete, {} left\n", phases.size(), hms(total), kept, hms(left));
  else
    put("Plan: {} phases, {} of device time\n", phases.size(), hms(total));
  for (std::size_t i = 0; i < phases.size(); ++i)
    put("  {:>2}. {:<14} {:>9}  {}\n", i + 1, phases[i].id, hms(phases[i].planned_s), phases[i].title);
  std::fflush(out_);
}

void TerminalView::phase_started(std::size_t index, std::size_t count, const std::string& id, const std::string& title,
                                 double) {
  index_ = index;
  count_ = count;
  fraction_ = 0;
  last_quarter_ = -1;
  done_planned_ = 0;
  for (std::size_t i = 0; i < index && i < planned_.size(); ++i) done_planned_ += planned_[i];
  // The wall ETA's speed is measured from the first phase this session runs: the operator's time
  // at the prompts, and a resume's phases done in an earlier session, are not its pace (a review
  // read "wall 173:15:01" after ten seconds at a prompt).
  if (!running_) {
    running_ = true;
    wall_start_ = wall_s();
    done_at_start_ = done_planned_;
  }
  if (!quiet_) {
    if (tty_) put("\r\033[K");
    put("[{}/{}] {}: {}\n", index + 1, count, id, title);
    std::fflush(out_);
  }
}

void TerminalView::draw(bool final_line) {
  double total = 0;
  for (double p : planned_) total += p;
  const double cur = index_ < planned_.size() ? planned_[index_] : 0;
  const double done = done_planned_ + fraction_ * cur;
  const double elapsed_wall = wall_s() - wall_start_;
  // Device seconds per wall second, once a second of this session has gone by (the first draws
  // come during bring-up, whose pace is not the procedure's).
  const double speed = elapsed_wall >= 1.0 ? (done - done_at_start_) / elapsed_wall : 0;
  const double left = total - done;
  const int width = 30;
  const int fill = static_cast<int>(fraction_ * width + 0.5);
  const std::string bar = std::string(static_cast<std::size_t>(fill), '#') + std::string(static_cast<std::size_t>(width - fill), '.');
  // The bar and its percentage are the phase's, said so beside the whole run's share of its
  // planned device time (a technician read "48%" of phase 7 as the run's: a review).
  put("{}  [{}] phase {}/{} {:3.0f}%  run {:3.0f}%  ETA device {}  wall {}{}", tty_ ? "\r\033[K" : "  ", bar, index_ + 1,
      count_, fraction_ * 100, total > 0 ? std::min(100.0, 100 * done / total) : 0.0, hms(left),
      speed > 0 ? hms(left / speed) : "--:--:--", final_line || !tty_ ? "\n" : "");
  std::fflush(out_);
}

void TerminalView::phase_progress(double fraction, double) {
  if (quiet_) return;
  fraction_ = std::min(std::max(fraction, 0.0), 1.0);
  const double now = wall_s();
  if (tty_) {
    if (now - last_draw_wall_ < 0.1) return;
    last_draw_wall_ = now;
    draw(false);
  } else {
    // Logs (CI): quarter marks for the long phases only.
    if (index_ >= planned_.size() || planned_[index_] < 60.0) return;
    const int q = static_cast<int>(fraction_ * 4);
    if (q == last_quarter_ || q == 0 || q >= 4) return;
    last_quarter_ = q;
    draw(true);
  }
}

void TerminalView::phase_finished(const std::string& id, const std::string& status, const std::string& message) {
  if (quiet_) return;
  if (tty_) put("\r\033[K");
  if (status != "done") {
    // "run06-U20 aborted: SIGINT received", not "aborted: aborted: ..." (the message often
    // starts with the status itself).
    const std::string lead = status + ": ";
    const std::string shown = message.rfind(lead, 0) == 0 ? message.substr(lead.size()) : message;
    put("  {} {}{}{}\n", id, status, shown.empty() ? "" : ": ", shown);
  }
  std::fflush(out_);
}

void TerminalView::log(const std::string& line) {
  if (quiet_) return;
  if (tty_) put("\r\033[K");
  put("{}\n", line);
  std::fflush(out_);
}

}  // namespace rig
