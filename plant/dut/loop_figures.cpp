#include "plant/dut/loop_figures.hpp"

#include <algorithm>
#include <cmath>

#include "plant/dut/loop_model.hpp"
#include "plant/dut/params.hpp"

namespace rig::plant {

double settling_time(const std::vector<double>& step, double dt, double band) {
  if (step.empty()) return 0;
  const double final_value = step.back();
  const double tol = band * std::abs(final_value);
  // Time of the last sample outside the band, plus one period (Besekersky & Popov:
  // t_рег is when |h(t) - h(inf)| stays within Δ).
  for (std::size_t k = step.size(); k-- > 0;)
    if (std::abs(step[k] - final_value) > tol) return static_cast<double>(k + 1) * dt;
  return 0;
}

double bandwidth_at(const std::vector<double>& freq, const std::vector<double>& amp, double level) {
  for (std::size_t k = 1; k < freq.size(); ++k) {
    if (amp[k] < level && amp[k - 1] >= level) {
      // interpolate in log-frequency between the two points
      const double a = (amp[k - 1] - level) / (amp[k - 1] - amp[k]);
      return std::exp(std::log(freq[k - 1]) + a * (std::log(freq[k]) - std::log(freq[k - 1])));
    }
  }
  return 0;
}

LoopFigures loop_figures(const toml::table* dut_cfg, const rig::FilterConfig& filter_in) {
  const DutParams p = load_dut_params(dut_cfg);
  const LoopModel model(p.loop, p.regulator);
  const LinearLoop lin = model.linear();
  FilterConfig filter = filter_in;
  filter.rate_hz = p.loop.loop_rate_hz;

  LoopFigures f;
  const double dt = 1.0 / p.loop.loop_rate_hz;
  const std::size_t n = static_cast<std::size_t>(0.05 * p.loop.loop_rate_hz);  // 50 ms
  f.step_x = loop_step(lin, n);
  f.step_y = apply_filter(filter, f.step_x);
  for (std::size_t k = 0; k < n; ++k) f.step_t_s.push_back(static_cast<double>(k) * dt);
  f.dc_gain = std::abs(loop_response(lin, 0.0) * filter_response(filter, 0.0));
  f.settling_time_s = settling_time(f.step_y, dt, f.settling_band);
  f.overshoot = std::max(0.0, *std::max_element(f.step_y.begin(), f.step_y.end()) / f.step_y.back() - 1);

  const double nyq = p.loop.loop_rate_hz / 2;
  for (double lf = 0; lf <= std::log10(nyq * 0.999); lf += 0.002) {
    const double fr = std::pow(10.0, lf);
    const std::complex<double> hx = loop_response(lin, fr);
    f.freq_hz.push_back(fr);
    f.amp_x.push_back(std::abs(hx));
    f.amp_y.push_back(std::abs(hx * filter_response(filter, fr)));
  }
  f.bandwidth_0p5_hz = bandwidth_at(f.freq_hz, f.amp_y, 0.5);
  f.bandwidth_3db_hz = bandwidth_at(f.freq_hz, f.amp_y, 1 / std::sqrt(2.0));
  return f;
}

}  // namespace rig::plant
