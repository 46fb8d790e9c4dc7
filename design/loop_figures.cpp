#include "design/loop_figures.hpp"

#include <algorithm>
#include <cmath>

#include "design/loop_model.hpp"

namespace rig::design {

namespace {

// The step is simulated over a window that starts at 50 ms (the paper's Fig. 6 span) and doubles
// until the response has settled in its first half: a filter with a low cut-off settles in
// seconds, and a fixed 50 ms window cut its settling time short (butter2@5 read 47.9 ms, about
// 93 ms simulated). The longest window is 409.6 s (the last doubling within 600 s), 4.1e6 steps
// of a 10 kHz loop, well under a second.
constexpr double kFirstWindowS = 0.05;
constexpr double kLongestWindowS = 600;
// The curves for plots and JSON keep at most this many points of a long window (every k-th).
constexpr std::size_t kCurvePoints = 5000;
// The amplitude grid: 500 points a decade from 1 Hz to Nyquist, extended a decade at a time
// below 1 Hz while the filtered response there is more than 1 % off its DC gain, so a cut-off
// below 1 Hz is on the grid (its 0.5 level read "0 Hz" when the grid began at 1 Hz).
constexpr double kGridStep = 0.002;
constexpr int kLowestDecade = -9;

std::vector<double> every_kth(const std::vector<double>& v, std::size_t k) {
  if (k <= 1) return v;
  std::vector<double> out;
  for (std::size_t i = 0; i < v.size(); i += k) out.push_back(v[i]);
  return out;
}

}  // namespace

LoopFigures loop_figures(const LoopParams& lp, const RegulatorParams& rp, const FilterConfig& filter_in) {
  const LoopModel model(lp, rp);
  const LinearLoop lin = model.linear();
  FilterConfig filter = filter_in;
  filter.rate_hz = lp.loop_rate_hz;

  LoopFigures f;
  const std::complex<double> h0 = loop_response(lin, 0.0) * response(filter, 0.0);
  f.dc_gain = std::abs(h0);
  const double dt = 1.0 / lp.loop_rate_hz;
  std::vector<double> x, y;
  for (auto n = static_cast<std::size_t>(kFirstWindowS * lp.loop_rate_hz);; n *= 2) {
    x = loop_step(lin, n);
    y = apply_filter(filter, x);
    // h(inf) is the DC gain, not the window's last sample, which a slow filter has not reached.
    f.settling_time_s = analysis::settling_time(y, dt, h0.real(), f.settling_band);
    f.step_window_s = static_cast<double>(n) * dt;
    if (f.settling_time_s <= f.step_window_s / 2) break;
    if (f.step_window_s * 2 > kLongestWindowS) {
      f.settled = false;  // still outside the band in the window's second half
      break;
    }
  }
  if (h0.real() != 0) f.overshoot = std::max(0.0, *std::max_element(y.begin(), y.end()) / h0.real() - 1);
  const std::size_t k = (y.size() + kCurvePoints - 1) / kCurvePoints;
  f.step_x = every_kth(x, k);
  f.step_y = every_kth(y, k);
  for (std::size_t i = 0; i < y.size(); i += std::max<std::size_t>(k, 1)) f.step_t_s.push_back(static_cast<double>(i) * dt);

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
  f.bandwidth_0p5_hz = bandwidth_at(f.freq_hz, f.amp_y, 0.5);
  f.bandwidth_3db_hz = bandwidth_at(f.freq_hz, f.amp_y, 1 / std::sqrt(2.0));
  return f;
}

}  // namespace rig::design
