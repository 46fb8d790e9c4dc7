#include "tests/plant/paper_procedure.hpp"

#include <cmath>

#include "plant/dut/noise.hpp"
#include "analysis/allan.hpp"
#include "analysis/rms.hpp"
#include "analysis/gost.hpp"

namespace rig::plant::calib {

namespace {
std::vector<double> record(EmulatedDut& d, double seconds, std::vector<double>* y = nullptr) {
  const auto n = static_cast<std::size_t>(std::llround(seconds * d.output_rate_hz()));
  std::vector<double> x(n);
  if (y) y->resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    double xi, yi;
    d.next(xi, yi);
    x[i] = xi;
    if (y) (*y)[i] = yi;
  }
  return x;
}
double mean(const std::vector<double>& v) {
  double s = 0;
  for (double e : v) s += e;
  return s / static_cast<double>(v.size());
}
}  // namespace

analysis::NoiseTerms allan_terms(const std::vector<double>& v, double rate_hz, std::vector<analysis::DevPoint>* adev,
                                 const std::string& taus) {
  analysis::DevOptions o;
  o.type = analysis::Deviation::OADEV;
  o.rate_hz = rate_hz;
  o.taus = analysis::parse_tau_grid(taus);
  const std::vector<analysis::DevPoint> pts = analysis::deviation(v, o);
  if (adev) *adev = pts;
  return analysis::noise_terms(pts, static_cast<double>(v.size()) / rate_hz);
}

double b_from_minimum(const std::vector<analysis::DevPoint>& adev, double tau_lo) {
  double m = 0;
  for (const auto& d : adev)
    if (d.tau_s >= tau_lo && (m == 0 || d.dev < m)) m = d.dev;
  return m / analysis::kBiasFactor;
}

Result run(EmulatedDut& dut, const Spec& spec) {
  Result r;
  noise::Rng table(spec.table_seed, 99);
  const double u10 = dut.params().orientation.u10_angle_deg;
  const double fs = dut.output_rate_hz();
  // A: 12 runs alternating U10/U20, each averaged over 100 s (METHOD.md (3), (4)).
  for (int i = 0; i < spec.runs; ++i) {
    const bool at_u10 = i % 2 == 0;
    dut.set_table_angle_deg(u10 + (at_u10 ? 0.0 : 180.0) + spec.repeat_sd_deg * table.normal());
    record(dut, spec.move_s);
    const double m = mean(record(dut, spec.run_s));
    (at_u10 ? r.x10 : r.x20).push_back(m);
  }
  for (std::size_t i = 0; i < r.x10.size(); ++i) {
    r.bias += (r.x10[i] + r.x20[i]) / 2;
    r.base_error += (r.x10[i] - r.x20[i]) / 2;
  }
  r.bias /= static_cast<double>(r.x10.size());
  r.base_error /= static_cast<double>(r.x10.size());
  // B: 30 min at U10, (max - min)/2 of the 100 s and 200 s means.
  dut.set_table_angle_deg(u10 + spec.repeat_sd_deg * table.normal());
  record(dut, spec.move_s);
  const std::vector<double> inrun = record(dut, spec.inrun_s);
  r.b_gost_100 = analysis::in_run_b(inrun, static_cast<std::size_t>(100 * fs)).value;
  r.b_gost_200 = analysis::in_run_b(inrun, static_cast<std::size_t>(200 * fs)).value;
  // C: raw capture, Allan noise terms of x and of the filtered y.
  std::vector<double> y;
  const std::vector<double> x = record(dut, spec.capture_s, &y);
  r.nt_x = allan_terms(x, fs, &r.adev_x, spec.taus);
  r.nt_y = allan_terms(y, fs, &r.adev_y, spec.taus);
  // RMS error: of the drift (the zero-signal mean removed), as the paper's x̂.
  const double mx = mean(x), my = mean(y);
  std::vector<double> dx(x.size()), dy(y.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    dx[i] = x[i] - mx;
    dy[i] = y[i] - my;
  }
  r.rms_x = analysis::rms(dx);
  r.rms_y = analysis::rms(dy);
  return r;
}

}  // namespace rig::plant::calib
