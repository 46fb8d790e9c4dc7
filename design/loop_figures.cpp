#include "design/loop_figures.hpp"

#include <algorithm>
#include <cmath>

#include "design/loop_model.hpp"

namespace rig::design {

LoopFigures loop_figures(const LoopParams& lp, const RegulatorParams& rp, const FilterConfig& filter_in) {
  const LoopModel model(lp, rp);
  const LinearLoop lin = model.linear();
  FilterConfig filter = filter_in;
  filter.rate_hz = lp.loop_rate_hz;

  LoopFigures f;
  const double dt = 1.0 / lp.loop_rate_hz;
  const std::size_t n = static_cast<std::size_t>(0.05 * lp.loop_rate_hz);  // 50 ms
  f.step_x = loop_step(lin, n);
  f.step_y = apply_filter(filter, f.step_x);
  for (std::size_t k = 0; k < n; ++k) f.step_t_s.push_back(static_cast<double>(k) * dt);
  f.dc_gain = std::abs(loop_response(lin, 0.0) * response(filter, 0.0));
  f.settling_time_s = settling_time(f.step_y, dt, f.settling_band);
  f.overshoot = std::max(0.0, *std::max_element(f.step_y.begin(), f.step_y.end()) / f.step_y.back() - 1);

  const double nyq = lp.loop_rate_hz / 2;
  for (double lf = 0; lf <= std::log10(nyq * 0.999); lf += 0.002) {
    const double fr = std::pow(10.0, lf);
    const std::complex<double> hx = loop_response(lin, fr);
    f.freq_hz.push_back(fr);
    f.amp_x.push_back(std::abs(hx));
    f.amp_y.push_back(std::abs(hx * response(filter, fr)));
  }
  f.bandwidth_0p5_hz = bandwidth_at(f.freq_hz, f.amp_y, 0.5);
  f.bandwidth_3db_hz = bandwidth_at(f.freq_hz, f.amp_y, 1 / std::sqrt(2.0));
  return f;
}

}  // namespace rig::design
