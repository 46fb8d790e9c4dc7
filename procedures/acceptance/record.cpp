#include "procedures/acceptance/record.hpp"

#include <filesystem>
#include <vector>

#include <fmt/format.h>

#include "rig/capture/capture.hpp"
#include "rig/core/dut_link.hpp"
#include "rig/core/errors.hpp"

namespace rig::acceptance {

double table_angle(const Profile& p, Orientation o) { return o == Orientation::U10 ? p.u10_deg : p.u20_deg; }

std::string run_phase_id(std::size_t index, Orientation o) { return fmt::format("run{:02d}-{}", index, to_string(o)); }
std::string in_run_phase_id(const Profile& p) { return std::string("in-run-") + to_string(p.in_run_orientation); }
std::string raw_phase_id(const Profile& p) { return std::string("raw-") + to_string(p.raw_orientation); }
std::string capture_rel(const std::string& phase_id) { return "captures/" + phase_id + ".cap"; }

namespace {

// The stream's pace against the profile's rate: a DUT that streams at another rate than the one
// the run stamps on its captures (a [dut.stream] rate_hz left at its default beside a 500 Hz DUT
// without a command channel, which cannot declare its own) gives every tau and PSD frequency off
// by the ratio, and nothing else would say so (an integrator's review). Judged on records of 10 s
// or more, where the stream's start (a command, the first frame) is a small part; a fifth off and
// a second beyond is no crystal's error. ConfigError: the rate is the configuration's.
void check_stream_pace(const std::string& name, uint64_t samples, double took_s, double rate_hz) {
  const double expected_s = static_cast<double>(samples) / rate_hz;
  if (expected_s < 10 || (took_s <= 1.2 * expected_s + 1 && took_s >= 0.8 * expected_s - 1)) return;
  throw ConfigError(fmt::format(
      "{}: {} samples took {:.4g} s of the rig's clock, {:.4g} s at the profile's rate_hz = {:g}: the DUT streams at "
      "about {:.4g} Hz, and every tau and PSD frequency of this run would be off by {:.3g}; the profile's rate_hz and "
      "the hardware file's [dut.stream] rate_hz must be the rate the DUT streams at",
      name, samples, took_s, expected_s, rate_hz, static_cast<double>(samples) / took_s, took_s / expected_s));
}

Recorded record_once(PhaseContext& ctx, const Profile& p, Orientation o, double seconds, const std::string& name,
                     const std::string& serial, std::vector<std::string>* partial, int attempt) {
  const uint64_t n_total = planned_samples(p, seconds);
  const std::string rel = capture_rel(name);
  std::filesystem::create_directories(ctx.out_dir + "/captures");
  capture::Header h;
  h.serial = serial;
  h.phase = name;
  h.orientation = to_string(o);
  h.started = iso8601_utc_now();
  h.rate_hz = p.rate_hz;
  // The filter y(t) went through: the profile's, which bring-up loaded, unless the DUT has no
  // command channel to load it with.
  const DutCommandChannel commands = ctx.dev.dut.command_channel();
  const std::string filter =
      commands.available ? p.filter_name : "not set: the DUT's own (no command channel: " + commands.reason + ")";
  h.extra = {{"profile", p.name},
             {"plant", ctx.dev.plant},
             {"table_deg", table_angle(p, o)},
             {"filter", filter},
             {"software", std::string("rig ") + RIG_VERSION}};
  capture::Writer w(ctx.out_dir + "/" + rel, h);
  // An earlier attempt's record: kept, and said where, and which: this process's retry after lost
  // samples, or an interrupted run's (a retry read "an interrupted attempt's": a technician's review).
  if (!w.set_aside().empty())
    ctx.log->warn("{}: {} already held a record ({}): kept as {}", name, rel,
                  attempt > 1 ? fmt::format("attempt {}'s, which lost samples", attempt - 1)
                              : std::string("an interrupted attempt's"),
                  std::filesystem::path(w.set_aside()).filename().string());

  Recorded r;
  r.capture = rel;
  ctx.dev.dut.reset_stats();
  std::vector<Sample> buf(static_cast<std::size_t>(std::max(1.0, p.rate_hz / 10)));  // 100 ms chunks
  double sx = 0, sy = 0, started_s = 0, ended_s = 0;
  bool streaming = false;
  try {
    ctx.dev.dut.start_stream(ctx.cancel);  // inside: a stop here leaves the capture's header, named too
    streaming = true;
    started_s = ctx.dev.clock.now_s();
    while (r.samples < n_total) {
      const std::size_t want = static_cast<std::size_t>(std::min<uint64_t>(buf.size(), n_total - r.samples));
      const std::size_t got = ctx.dev.dut.read(std::span<Sample>(buf.data(), want), ctx.cancel);
      w.append(std::span<const Sample>(buf.data(), got));
      for (std::size_t i = 0; i < got; ++i) {
        sx += buf[i].x_g;
        sy += buf[i].y_g;
      }
      r.samples += got;
      ctx.report(static_cast<double>(r.samples) / static_cast<double>(n_total));
    }
    ended_s = ctx.dev.clock.now_s();
    streaming = false;  // stopped once, whatever the stop says
    ctx.dev.dut.stop_stream();
    w.close();
  } catch (...) {
    // Named first, and the first failure is the one that goes on: a close that failed too (a disk
    // that refused the samples refuses their sync) replaced it and left the capture out of the
    // seal (a review: an ERROR folder sealed so failed `rig verify`). So is a capture recorded in
    // full whose stop or close failed.
    if (partial) partial->push_back(rel);
    if (streaming) {
      try {
        ctx.dev.dut.stop_stream();
      } catch (const std::exception& e) {  // the safe state stops it again
        ctx.log->warn("{}: stopping the DUT's stream after the failure: {}", name, e.what());
      }
    }
    try {
      w.close();  // keep what was recorded; the retry renames it aside (after a failed close: nothing to do)
    } catch (const std::exception& e) {
      ctx.log->warn("{}: {}", name, e.what());
    }
    throw;
  }
  // The capture's name too: the checkpoint about to name it must not outlive it in a power cut.
  fsync_folder(std::filesystem::path(ctx.out_dir + "/" + rel).parent_path().string());
  r.written = stamp_of(ctx.out_dir + "/" + rel);
  const LinkStats st = ctx.dev.dut.stats();
  r.lost = st.lost;
  r.gaps = st.gaps;
  r.duplicates = st.duplicates;
  r.mean_x = r.samples ? sx / static_cast<double>(r.samples) : 0;
  r.mean_y = r.samples ? sy / static_cast<double>(r.samples) : 0;
  check_stream_pace(name, r.samples + r.lost, ended_s - started_s, p.rate_hz);  // lost samples took their time too
  return r;
}

}  // namespace

Recorded position_and_record(PhaseContext& ctx, const Profile& p, Orientation o, double seconds,
                             const std::string& name, const std::string& serial, std::vector<std::string>* partial) {
  for (int attempt = 1;; ++attempt) {
    ctx.log->info("{}: table to {} ({:.4f} deg)", name, to_string(o), table_angle(p, o));
    // On the terminal too: the technician beside the table sees each turn announced (a review:
    // the moves were in run.log only).
    if (ctx.progress) ctx.progress->log(fmt::format("  table to {} ({:.4f}°)", to_string(o), table_angle(p, o)));
    ctx.dev.table.move_to(table_angle(p, o), ctx.cancel);
    ctx.dev.clock.sleep_for(p.settle_s, ctx.cancel);  // let the loop and the mount settle
    Recorded r = record_once(ctx, p, o, seconds, name, serial, partial, attempt);
    r.attempts = attempt;
    if (r.lost <= p.max_lost_samples) {
      ctx.log->info("{}: {} samples, mean x {:.6e} g, {} lost in {} gap(s)", name, r.samples, r.mean_x, r.lost, r.gaps);
      return r;
    }
    const std::string what = fmt::format("capture {}: {} samples lost in {} gap(s) (limit {})", name, r.lost, r.gaps,
                                         p.max_lost_samples);
    if (attempt > p.retries) {
      if (partial) partial->push_back(r.capture);  // kept as recorded, gaps and all
      throw HardwareError(what + "; no retries left");
    }
    ctx.log->warn("{}; retrying ({}/{})", what, attempt, p.retries);
    // Which attempt comes, said where the bar starts over (a technician's review: the bar went
    // back with nothing naming the attempt).
    if (ctx.progress)
      ctx.progress->log(fmt::format("  {}: retrying, attempt {} of {}", what, attempt + 1,
                                    p.retries + 1));
  }
}

}  // namespace rig::acceptance
