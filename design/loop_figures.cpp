#include "design/loop_figures.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "design/loop_model.hpp"

namespace rig::design {

namespace {

// The step is simulated here, not by loop_step and apply_filter (design/loop_model.hpp,
// filter.hpp), as one run continued across its windows; it takes their operations in their
// order, so their values (LoopFigures.TheStepIsLoopStepThroughTheFilter checks it bit for bit).
// The step is simulated from 50 ms (the paper's Fig. 6 span), its window doubled until the
// response has settled in its first half: a filter with a low cut-off settles in seconds, and a
// fixed 50 ms window cut its settling time short (butter2@5 read 47.9 ms, about 93 ms simulated).
// One run, continued across the doublings. Capped by samples, not seconds, so its cost does not
// grow with the loop rate (a 1 MHz loop took 65 s and 8 GB with a 600 s cap, a code review):
// 4 096 000 steps, 409.6 s of a 10 kHz loop, a few tenths of a second.
constexpr double kFirstWindowS = 0.05;
constexpr std::size_t kMostSteps = 4'096'000;
// The curves for plots and JSON keep at most this many points, every s-th sample (s a power of 2).
constexpr std::size_t kCurvePoints = 5000;
// The amplitude grid: 500 points a decade from 1 Hz to Nyquist, extended a decade at a time
// below 1 Hz while the filtered response there is more than 1 % off its DC gain, so a cut-off
// below 1 Hz is on the grid (its 0.5 level read "0 Hz" when the grid began at 1 Hz). The floor
// is below the lowest cut-off a filter may have (filter_select refuses a butter1 under about
// 2e-10 Hz at 10 kHz, whose DC gain its rounding no longer holds; 1e-9 Hz read "0 Hz" at -9).
constexpr double kGridStep = 0.002;
constexpr int kLowestDecade = -15;

// The largest |pole| of the linear loop: past 1 it does not settle, and a step that runs into inf
// and NaN has no figures (its NaN samples read as inside the band, a code review).
double largest_pole(const LinearLoop& l) {
  const Eigen::VectorXcd ev = Eigen::EigenSolver<Eigen::MatrixXd>(l.A, false).eigenvalues();
  double r = 0;
  for (Eigen::Index i = 0; i < ev.size(); ++i) r = std::max(r, std::abs(ev(i)));
  return r;
}

}  // namespace

LoopFigures loop_figures(const LoopParams& lp, const RegulatorParams& rp, const FilterConfig& filter_in) {
  const LoopModel model(lp, rp);
  const LinearLoop lin = model.linear();
  FilterConfig filter = filter_in;
  filter.rate_hz = lp.loop_rate_hz;

  LoopFigures f;
  f.largest_pole = largest_pole(lin);
  if (!f.stable()) {  // no step to simulate: it would run into inf and NaN to the cap
    f.settled = false;
    return f;
  }
  const std::complex<double> h0 = loop_response(lin, 0.0) * response(filter, 0.0);
  f.dc_gain = std::abs(h0);
  const double dt = 1.0 / lp.loop_rate_hz, final = h0.real(), tol = f.settling_band * std::abs(final);

  // The loop's state z and the filter's sections, stepped as loop_step and apply_filter do (the
  // same operations in the same order, so the same values), keeping what the figures need: the
  // last sample outside the band, the largest y / final, and the curves' every s-th sample.
  Eigen::VectorXd z = Eigen::VectorXd::Zero(lin.A.rows()), next(lin.A.rows());
  std::vector<Section> sections;
  if (filter.enabled)
    for (const Biquad& b : filter.sections) sections.push_back({b});
  std::size_t last_out = 0, stride = 1;  // last_out: one past the last sample outside the band
  double peak = -HUGE_VAL;
  std::size_t n = 0, window = std::max<std::size_t>(1, static_cast<std::size_t>(kFirstWindowS * lp.loop_rate_hz));
  for (;;) {
    for (; n < window; ++n) {
      const double x = lin.C * z;
      next.noalias() = lin.A * z;
      z = next + lin.B;
      double y = x;
      for (Section& s : sections) y = s.step(y);
      if (!(std::abs(y - final) <= tol)) last_out = n + 1;  // a NaN is outside
      if (final != 0) peak = std::max(peak, y / final);
      if (n % stride == 0) {
        f.step_t_s.push_back(static_cast<double>(n) * dt);
        f.step_x.push_back(x);
        f.step_y.push_back(y);
        if (f.step_t_s.size() > kCurvePoints) {  // every other point kept, the stride doubled
          stride *= 2;
          for (std::vector<double>* v : {&f.step_t_s, &f.step_x, &f.step_y}) {
            for (std::size_t i = 0; 2 * i < v->size(); ++i) (*v)[i] = (*v)[2 * i];
            v->resize((v->size() + 1) / 2);
          }
        }
      }
    }
    f.settling_time_s = static_cast<double>(last_out) * dt;
    f.step_window_s = static_cast<double>(n) * dt;
    if (2 * last_out <= n) break;
    if (n >= kMostSteps) {
      f.settled = false;  // still outside the band in the window's second half: a lower bound
      break;
    }
    window = std::min(2 * n, kMostSteps);  // the last window the cap itself, whatever the rate
  }
  if (final != 0 && std::isfinite(peak)) f.overshoot = std::max(0.0, peak - 1);

  const auto amp_y_at = [&](double fr) { return std::abs(loop_response(lin, fr) * response(filter, fr)); };
  int lowest = 0;
  while (lowest > kLowestDecade && std::abs(amp_y_at(std::pow(10.0, lowest)) - f.dc_gain) > 0.01 * f.dc_gain) --lowest;
  const auto add = [&](double fr) {
    const std::complex<double> hx = loop_response(lin, fr);
    f.freq_hz.push_back(fr);
    f.amp_x.push_back(std::abs(hx));
    f.amp_y.push_back(std::abs(hx * response(filter, fr)));
  };
  for (int i = -lowest * static_cast<int>(std::lround(1 / kGridStep)); i > 0; --i) add(std::pow(10.0, -i * kGridStep));
  const double nyq = lp.loop_rate_hz / 2;
  for (double lf = 0; lf <= std::log10(nyq * 0.999); lf += kGridStep) add(std::pow(10.0, lf));
  // The grid's crossing, then the exact one between its two grid points: the interpolation held
  // about 5 significant digits and 6 are printed (butter4@700's 0.5 level read 615.551 Hz for
  // 615.5535 Hz: a metrologist's review). Bisection in log frequency on the response itself.
  const auto crossing = [&](double level) {
    const double grid = bandwidth_at(f.freq_hz, f.amp_y, level);
    const auto above = std::upper_bound(f.freq_hz.begin(), f.freq_hz.end(), grid);
    if (!(grid > 0) || above == f.freq_hz.begin() || above == f.freq_hz.end()) return grid;
    double lo = *(above - 1), hi = *above;
    if (!(amp_y_at(lo) >= level && amp_y_at(hi) < level)) return grid;
    for (int i = 0; i < 200 && hi > lo * (1 + 1e-13); ++i) {
      const double mid = std::sqrt(lo * hi);
      (amp_y_at(mid) >= level ? lo : hi) = mid;
    }
    return std::sqrt(lo * hi);
  };
  f.bandwidth_0p5_hz = crossing(0.5);
  f.bandwidth_3db_hz = crossing(1 / std::sqrt(2.0));
  return f;
}

}  // namespace rig::design
