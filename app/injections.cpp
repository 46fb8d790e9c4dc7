#include "app/injections.hpp"

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <charconv>
#include <cmath>
#include <limits>
#include <thread>

#include <fmt/format.h>
#include <spdlog/logger.h>

#include "app/whole_number.hpp"
#include "plant/emulated/world.hpp"
#include "rig/core/errors.hpp"

namespace rig::cli {

namespace {
// A signal --inject can send this process, by name.
int injected_signal(const std::string& kind) {
  if (kind == "sigint") return SIGINT;
  if (kind == "sigterm") return SIGTERM;
  if (kind == "sigkill") return SIGKILL;
  return 0;
}
}  // namespace

std::vector<Injection> parse_injections(const std::vector<std::string>& inj) {
  // The whole text, decimal (std::from_chars: no blanks, no sign, no hex), finite.
  auto number = [](const std::string& s, const std::string& text) {
    double v = -1;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v) || v < 0)
      throw ConfigError("--inject '" + s + "': '" + text + "' is not a device time in seconds (a decimal number >= 0)");
    return v;
  };
  auto count = [](const std::string& s, const std::string& text, std::uint32_t least) {
    const auto v = whole_number(text, least, std::numeric_limits<std::uint32_t>::max());
    if (!v)
      throw ConfigError("--inject '" + s + "': '" + text + "' is not a whole number in [" + std::to_string(least) +
                        ", " + std::to_string(std::numeric_limits<std::uint32_t>::max()) +
                        "] (decimal, no leading zero: drop@SEQ:COUNT)");
    return static_cast<std::uint32_t>(*v);
  };
  std::vector<Injection> out;
  for (const std::string& s : inj) {
    const auto at = s.find('@');
    if (at == std::string::npos) throw ConfigError("--inject '" + s + "': expected KIND@ARG");
    const std::string kind = s.substr(0, at), arg = s.substr(at + 1);
    Injection j;
    j.text = s;
    if ((kind == "sigint" || kind == "sigterm") && arg == "end") {
      j.kind = Injection::Kind::SignalAtEnd;
      j.signal = injected_signal(kind);
    } else if (kind == "estop") {
      j.at_s = number(s, arg);
    } else if (const int sig = injected_signal(kind)) {
      j.kind = Injection::Kind::Signal;
      j.signal = sig;
      j.at_s = number(s, arg);
    } else if (kind == "drop") {
      const auto c = arg.find(':');
      if (c == std::string::npos) throw ConfigError("--inject '" + s + "': expected drop@SEQ:COUNT");
      j.kind = Injection::Kind::Drop;
      j.seq = count(s, arg.substr(0, c), 0);
      j.count = count(s, arg.substr(c + 1), 1);
    } else {
      throw ConfigError("--inject '" + s +
                        "': unknown fault (estop@T, sigint@T, sigterm@T, sigkill@T, sigint@end, sigterm@end, "
                        "drop@SEQ:COUNT)");
    }
    out.push_back(j);
  }
  return out;
}

std::vector<std::string> sample_losses(const std::vector<std::string>& inject) {
  std::vector<std::string> drops;
  for (const std::string& f : inject)
    if (f.rfind("drop@", 0) == 0) drops.push_back(f);
  return drops;
}

int apply_injections(plant::EmulatedPlant& w, const std::vector<Injection>& inj, const CancelToken& taken) {
  int signal_at_end = 0;
  // The plant holds its device time until the process has taken the signal (the signal watcher's
  // thread trips `taken`), so the run stops at the same sample every time: it ran on for a few
  // milliseconds of wall time, seconds of device time, and sigint@20 kept 1 or 2 phases (a
  // technician's review). Bounded: a signal nobody takes leaves the plant going after 2 s.
  const auto signal_and_wait = [taken](int sig) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    ::kill(::getpid(), sig);
    while (!taken.requested() && std::chrono::steady_clock::now() < until)
      std::this_thread::sleep_for(std::chrono::microseconds(100));
  };
  for (const Injection& j : inj) switch (j.kind) {
      case Injection::Kind::SignalAtEnd: signal_at_end = j.signal; break;
      case Injection::Kind::Estop: w.trip_estop_at(j.at_s); break;
      case Injection::Kind::Signal: w.at(j.at_s, [signal_and_wait, sig = j.signal] { signal_and_wait(sig); }); break;
      case Injection::Kind::Drop: w.inject_drop(j.seq, j.count); break;
    }
  return signal_at_end;
}

std::vector<std::string> faults_past_the_plan(const std::vector<Injection>& inj, double planned_s) {
  std::vector<std::string> notes;
  for (const Injection& j : inj)
    // Well past: bring-up and the table's settling add seconds the plan does not count (a review:
    // estop@225 on ci's plan of 221 s was said not to fire, and fired at 225 s).
    if ((j.kind == Injection::Kind::Signal || j.kind == Injection::Kind::Estop) && j.at_s > 1.25 * planned_s + 60)
      notes.push_back(fmt::format("--inject {} lies well past the plan's {:.0f} s of device time: it fires only if the "
                                  "run takes that much longer (the run says whether it fired)",
                                  j.text, planned_s));
  return notes;
}

void say_faults_that_did_not_fire(plant::EmulatedPlant& w, const std::vector<Injection>& inj, bool from_run_json,
                                  spdlog::logger& log) {
  const double end_s = w.clock().now_s();
  for (const Injection& j : inj)
    if ((j.kind == Injection::Kind::Signal || j.kind == Injection::Kind::Estop) && j.at_s > end_s)
      log.error("--inject {} did not fire: the run ended at {:.3f} s of device time", j.text, end_s);
  const std::vector<std::uint64_t> hits = w.drop_hits();
  std::size_t k = 0;  // the plant's drops are the Drop injections, in order
  for (const Injection& j : inj)
    if (j.kind == Injection::Kind::Drop && k++ < hits.size() && hits[k - 1] == 0)
      log.error("{} {} did not fire: the DUT streamed none of samples {}..{} (the stream is on only while "
                "a recording or the loop test runs; the run's records say which sequence numbers they hold)",
                from_run_json ? "run.json's fault" : "--inject", j.text, j.seq,
                static_cast<std::uint64_t>(j.seq) + j.count - 1);
}

}  // namespace rig::cli
