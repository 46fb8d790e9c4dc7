// The closed loop's figures measured from recorded step responses (the DUT's loop test,
// docs/can-protocol.md "Loop test"): the paper's criterion 2 (docs/method.md "Spectral analysis and
// the output filter") -- settling time t_рег and bandwidth at the 0.5 level -- read off what
// the DUT did rather than a model of it, with uncertainties from the scatter of repeated steps.
// Pure computation, no I/O.
#pragma once
#include <cstddef>
#include <span>
#include <vector>

namespace rig::analysis {

// Criterion 2's settling band: 5 % of the final value, the one convention of the design model
// (design/filter.hpp kSettlingBand is this constant; why 5 %: there) and of the passport.
inline constexpr double kStepSettlingBand = 0.05;

// A recorded step normalised to a unit step: (r - baseline) / amplitude, from the sample the
// step was applied in (index `pre`) on; the baseline is the mean of the `pre` samples before.
// Throws std::invalid_argument when pre is 0 or leaves no sample after it, or amplitude is 0.
std::vector<double> unit_step(std::span<const double> r, std::size_t pre, double amplitude);

// The final value of a step response: the mean of its last `tail_fraction` (at least one
// sample), so that noise on the last sample does not move the settling band.
double final_value(std::span<const double> h, double tail_fraction = 0.2);

// Settling time of a step response sampled every dt: the time after which it stays within
// band * |final| of `final`, i.e. the last sample outside the band plus one period (0 when no
// sample is outside; a sample that is not a number is outside). Its resolution is dt.
double settling_time(std::span<const double> h, double dt, double final, double band = kStepSettlingBand);

// The amplitude response |H(f)| / |H(0)| of the system behind a step response: for a step
// input the first difference of the output is the impulse response, whose DFT is H at any f
// (evaluated directly, no zero-padding); H(0) is taken as `final` (the DC gain). Frequencies
// step_hz, 2 step_hz, ... up to rate_hz / 2.
struct AmplitudeCurve {
  std::vector<double> f_hz, amp;
};
AmplitudeCurve step_amplitude_response(std::span<const double> h, double rate_hz, double final, double step_hz = 1.0);
// That grid: step_hz, 2 step_hz, ... up to rate_hz / 2 (each the one before plus step_hz).
std::vector<double> amplitude_grid(double rate_hz, double step_hz = 1.0);
// The same amplitude response at the frequencies f_hz only (points of that grid, for the same
// values): each value has the bits step_amplitude_response gives at its frequency.
AmplitudeCurve step_amplitude_at(std::span<const double> h, double rate_hz, double final, std::span<const double> f_hz);
// crossing_frequency(level) of step_amplitude_response's curve, the same value, evaluating the
// grid only up to the crossing (the rest of a 1 Hz grid to rate_hz / 2 is most of the work).
double step_crossing_frequency(std::span<const double> h, double rate_hz, double final, double level,
                               double step_hz = 1.0);

// First frequency where the amplitude curve `amp` (at ascending `f_hz`) falls through `level`
// (0.5 for criterion 2, 1/sqrt(2) for -3 dB), interpolated in log-frequency between the two
// points around the crossing; 0 if it never does. The design model reads its figures with the
// same two functions (design/filter.hpp bandwidth_at; design/loop_figures.cpp, settling_time
// with the model's DC gain as the final value).
double crossing_frequency(std::span<const double> f_hz, std::span<const double> amp, double level);

// The figures of one recorded step (normalised, see unit_step), at rate_hz.
struct StepFigures {
  double final_value = 0;
  double settling_time_s = 0;
  double bandwidth_0p5_hz = 0;
  double overshoot = 0;  // peak over the final value, fraction
  AmplitudeCurve amplitude;
};
StepFigures step_figures(std::span<const double> h, double rate_hz, double band = kStepSettlingBand);
// The same figures with the amplitude curve at curve_f_hz only (points of amplitude_grid, e.g.
// the ones a report plots): the same values there, and the bandwidth read as above.
StepFigures step_figures(std::span<const double> h, double rate_hz, double band, std::span<const double> curve_f_hz);

// A figure measured over n repeated steps: their mean, and the interval
// mean +- sqrt((t_{0.975, n-1} s / sqrt(n))^2 + (resolution / 2)^2): Student's 95 % interval of
// the mean (GOST R 8.736, as for the bias) widened by the figure's resolution (a rectangular
// +-resolution/2). With one step only the resolution term remains.
struct RepeatedFigure {
  double value = 0, lo = 0, hi = 0;
  double sd = 0;  // sample standard deviation over the steps (0 for one step)
  std::size_t n = 0;
};
// Throws std::invalid_argument for an empty set.
RepeatedFigure repeated_figure(std::span<const double> per_step, double resolution);

}  // namespace rig::analysis
