#include "analysis/psd.hpp"
#include "analysis/median.hpp"

#include "analysis/parallel.hpp"

#include <fftw3.h>

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <cstdio>
#include <bit>
#include <limits>
#include <memory>
#include <numbers>
#include <numeric>
#include <mutex>
#include <thread>
#include <span>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rig::analysis {

Window parse_window(const std::string& s) {
  if (s == "hann") return Window::Hann;
  if (s == "hamming") return Window::Hamming;
  if (s == "blackman") return Window::Blackman;
  if (s == "rect" || s == "rectangular") return Window::Rectangular;
  throw std::invalid_argument("unknown window '" + s + "' (hann|hamming|blackman|rect)");
}

const char* to_string(Window w) {
  switch (w) {
    case Window::Hann: return "hann";
    case Window::Hamming: return "hamming";
    case Window::Blackman: return "blackman";
    case Window::Rectangular: return "rect";
  }
  return "?";
}

namespace {

std::vector<double> make_window(Window w, std::size_t n) {
  std::vector<double> v(n, 1.0);
  const double pi2 = 2 * std::numbers::pi / static_cast<double>(n);  // periodic (DFT-even) windows
  for (std::size_t i = 0; i < n; ++i) {
    const double t = pi2 * static_cast<double>(i);
    switch (w) {
      case Window::Hann: v[i] = 0.5 - 0.5 * std::cos(t); break;
      case Window::Hamming: v[i] = 0.54 - 0.46 * std::cos(t); break;
      case Window::Blackman: v[i] = 0.42 - 0.5 * std::cos(t) + 0.08 * std::cos(2 * t); break;
      case Window::Rectangular: break;
    }
  }
  return v;
}

// FFTW's planner is not thread-safe; plans are created under this lock.
std::mutex& planner_mutex() {
  static std::mutex m;
  return m;
}

struct PlanDeleter {
  void operator()(fftw_plan_s* p) const {
    std::lock_guard lock(planner_mutex());
    fftw_destroy_plan(p);
  }
};

}  // namespace

Psd welch(std::span<const double> x, double rate_hz, const WelchOptions& opt) {
  return welch(SpanSource(x), rate_hz, opt);
}

std::size_t welch_segment(std::uint64_t n, const WelchOptions& opt) {
  if (opt.segment) return opt.segment;
  return std::clamp<std::size_t>(std::bit_floor(std::max<std::uint64_t>(n / 8, 1)), 256, 65536);
}

Psd welch(const ChunkSource& src, double rate_hz, const WelchOptions& opt) {
  const std::uint64_t n_total = src.size();
  if (!(rate_hz > 0)) throw std::invalid_argument("welch: rate must be positive");
  if (!(opt.overlap >= 0 && opt.overlap <= 0.95)) throw std::invalid_argument("welch: overlap must be in [0, 0.95]");
  const std::size_t seg = welch_segment(n_total, opt);
  if (seg < 8) throw std::invalid_argument("welch: segment must be at least 8 points");
  if (n_total < seg)
    throw std::invalid_argument("welch: " + std::to_string(n_total) + " samples are fewer than one segment of " +
                                std::to_string(seg));
  const auto step = std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(seg * (1 - opt.overlap))));
  const std::vector<double> w = make_window(opt.window, seg);
  double s2 = 0;
  for (double v : w) s2 += v * v;

  const std::size_t nb = seg / 2 + 1;
  Psd p;
  p.segment = seg;
  p.rate_hz = rate_hz;
  p.psd.assign(nb, 0.0);
  const std::uint64_t n_seg = (n_total - seg) / step + 1;
  p.segments = static_cast<std::size_t>(n_seg);

  // The segments are cut into a fixed number of blocks (the sum does not depend on the thread
  // count), each with its own plan and buffers; the blocks' sums are added in order. Within a
  // block only the new `step` values of each segment are read (the overlap is kept).
  constexpr std::uint64_t kBlocks = 8;
  std::vector<std::vector<double>> part(kBlocks);
  auto run_block = [&](std::size_t b) {
    const std::uint64_t s0 = n_seg * b / kBlocks, s1 = n_seg * (b + 1) / kBlocks;
    std::vector<double>& acc = part[b];
    acc.assign(nb, 0.0);
    if (s0 >= s1) return;
    std::vector<double> in(seg), x(seg);
    auto* out = static_cast<fftw_complex*>(fftw_malloc(sizeof(fftw_complex) * nb));
    std::unique_ptr<fftw_complex, decltype(&fftw_free)> out_guard(out, &fftw_free);
    std::unique_ptr<fftw_plan_s, PlanDeleter> plan;
    {
      std::lock_guard lock(planner_mutex());
      plan.reset(fftw_plan_dft_r2c_1d(static_cast<int>(seg), in.data(), out, FFTW_ESTIMATE));
    }
    if (!plan) throw std::runtime_error("welch: FFTW could not plan a transform of " + std::to_string(seg));
    auto read = [&](std::uint64_t pos, std::span<double> dst) {
      for (std::size_t got = 0; got < dst.size();) {
        const std::size_t r = src.read_at(pos + got, dst.subspan(got));
        if (r == 0) throw std::runtime_error("welch: source ended early at " + std::to_string(pos + got));
        got += r;
      }
    };
    for (std::uint64_t k = s0; k < s1; ++k) {
      if (opt.poll) opt.poll();
      const std::uint64_t start = k * step;
      if (k > s0 && step < seg) {  // slide: keep the overlap, read the rest
        std::copy(x.begin() + static_cast<std::ptrdiff_t>(step), x.end(), x.begin());
        read(start + (seg - step), std::span<double>(x).subspan(seg - step));
      } else {
        read(start, std::span<double>(x));
      }
      double mean = 0;
      if (opt.detrend_mean) {
        for (std::size_t i = 0; i < seg; ++i) mean += x[i];
        mean /= static_cast<double>(seg);
      }
      for (std::size_t i = 0; i < seg; ++i) in[i] = (x[i] - mean) * w[i];
      fftw_execute_dft_r2c(plan.get(), in.data(), out);
      for (std::size_t q = 0; q < nb; ++q) acc[q] += out[q][0] * out[q][0] + out[q][1] * out[q][1];
    }
  };
  const unsigned threads =
      std::min<unsigned>(opt.threads ? opt.threads : std::max(1u, std::thread::hardware_concurrency()), kBlocks);
  detail::parallel_for(kBlocks, threads, run_block);
  for (const auto& a : part)
    for (std::size_t q = 0; q < nb; ++q) p.psd[q] += a[q];
  {  // the bins' degrees of freedom (Psd::dof): the window's overlap correlation at j steps
    double v = 1;
    const double k_seg = static_cast<double>(p.segments);
    for (std::uint64_t j = 1; j < n_seg && j * step < seg; ++j) {
      double r = 0;
      for (std::size_t i = 0; i + j * step < seg; ++i) r += w[i] * w[i + j * step];
      r /= s2;
      v += 2 * (1 - static_cast<double>(j) / k_seg) * r * r;
    }
    p.dof = 2 * k_seg / v;
  }
  const double scale = 1.0 / (rate_hz * s2 * static_cast<double>(p.segments));
  p.f_hz.resize(nb);
  p.asd.resize(nb);
  for (std::size_t k = 0; k < nb; ++k) {
    const bool edge = k == 0 || (seg % 2 == 0 && k == nb - 1);
    p.psd[k] *= scale * (edge ? 1.0 : 2.0);  // one-sided: fold negative frequencies
    p.f_hz[k] = rate_hz * static_cast<double>(k) / static_cast<double>(seg);
    p.asd[k] = std::sqrt(p.psd[k]);
  }
  p.enbw_hz = rate_hz * static_cast<double>(seg) * s2 / std::pow(std::accumulate(w.begin(), w.end(), 0.0), 2) /
              static_cast<double>(seg);
  return p;
}

std::vector<Peak> find_peaks(const Psd& p, double min_prominence_db, std::size_t max_peaks, double false_alarm) {
  const std::size_t n = p.psd.size();
  std::vector<double> db(n);
  for (std::size_t i = 0; i < n; ++i) db[i] = 10 * std::log10(std::max(p.psd[i], 1e-300));
  std::vector<Peak> peaks;
  // Bin 0 is the segments' removed mean, no spectrum: bin 1 rising above it is no maximum, and a
  // falling spectrum (a drift, a random walk) read as a peak at the first bin (a review: 21 dB "at
  // 0.12 Hz" for a ramp). A peak rises above a real bin on its left; the walks stop short of bin 0.
  constexpr std::size_t first = 1;
  // The ratio to the local median that noise alone exceeds in one of the spectrum's bins with
  // probability false_alarm (a Bonferroni split over the bins): chi2(dof) quantile over its median.
  double ratio = 0;
  if (false_alarm > 0 && p.dof > 0 && p.dof < kPeakNoiseRuleDof && n > first + 2) {
    const boost::math::chi_squared c(p.dof);
    ratio = boost::math::quantile(boost::math::complement(c, false_alarm / static_cast<double>(n - first))) /
            boost::math::median(c);
  }
  std::vector<double> near;
  auto above_noise = [&](std::size_t i) {
    if (ratio <= 0) return true;
    constexpr std::size_t kHalf = 64, kOwn = 3;  // the window's main lobe is at most +-3 bins
    near.clear();
    for (std::size_t j = std::max(first, i > kHalf ? i - kHalf : first); j < std::min(n, i + kHalf + 1); ++j)
      if (j + kOwn < i || j > i + kOwn) near.push_back(p.psd[j]);
    if (near.size() < 8) return true;  // too few bins around it to say: the prominence decides
    return p.psd[i] >= ratio * upper_median(std::move(near));
  };
  for (std::size_t i = first + 1; i + 1 < n; ++i) {
    if (!(db[i] > db[i - 1] && db[i] >= db[i + 1])) continue;
    // Walk out to higher ground on each side, tracking the lowest point on the way.
    double left_min = db[i], right_min = db[i];
    for (std::size_t j = i; j-- > first;) {
      if (db[j] > db[i]) break;
      left_min = std::min(left_min, db[j]);
    }
    for (std::size_t j = i + 1; j < n; ++j) {
      if (db[j] > db[i]) break;
      right_min = std::min(right_min, db[j]);
    }
    const double prom = db[i] - std::max(left_min, right_min);
    if (prom >= min_prominence_db && above_noise(i)) peaks.push_back({p.f_hz[i], p.psd[i], prom});
  }
  std::sort(peaks.begin(), peaks.end(), [](const Peak& a, const Peak& b) { return a.prominence_db > b.prominence_db; });
  if (peaks.size() > max_peaks) peaks.resize(max_peaks);
  return peaks;
}

double white_level(const Psd& p, double f_lo, double f_hi) {
  std::vector<double> v;
  for (std::size_t k = 1; k < p.psd.size(); ++k)
    if (p.f_hz[k] >= f_lo && p.f_hz[k] <= f_hi) v.push_back(p.psd[k]);
  if (v.empty()) throw std::invalid_argument("white_level: no PSD bins in the band");
  const double med = upper_median(std::move(v));
  // Each bin is ~ h0 chi2(k)/k with k its equivalent degrees of freedom (Psd::dof: 2 per segment,
  // fewer where overlapping segments are correlated; Welch 1967): divide by the median of that.
  // With 2 * segments, overlap ignored, the level read 2 % low at 90 % overlap (a metrologist's
  // review: 0.978 of 2 sigma^2/fs on white noise).
  const double k = p.dof > 0 ? p.dof : 2.0 * static_cast<double>(std::max<std::size_t>(p.segments, 1));
  const double med_ratio = boost::math::median(boost::math::chi_squared(k)) / k;
  return med / med_ratio;
}

std::string psd_n_note(double allan_n, double psd_n, bool psd_fit_ok, double f_lo, double f_hi) {
  if (!(allan_n > 0)) return {};
  char what[512];
  if (psd_n > 0) {
    const double ratio = psd_n / allan_n;
    if (!(ratio > 1.5 || ratio < 1 / 1.5)) return {};
    std::snprintf(what, sizeof what,
                  "psd: N from the PSD model (%.3g) is %.2fx the Allan N (%.3g) over %.3g..%.3g Hz: the two "
                  "disagree; one reads as N what neither model has a term for (a tone or a band of interference "
                  "in that band or in the taus the Allan model fitted, or noise that is not white): see the PSD's "
                  "peaks and the Allan curve's ripple",
                  psd_n, ratio, allan_n, f_lo, f_hi);
    return what;
  }
  if (!psd_fit_ok) return {};
  std::snprintf(what, sizeof what,
                "psd: the PSD model gives N no share over %.3g..%.3g Hz (its other terms fill that band): it "
                "neither confirms nor contradicts the Allan N (%.3g)",
                f_lo, f_hi, allan_n);
  return what;
}

PsdTerms psd_noise_fit(const Psd& p, double f_lo, double f_hi, std::span<const Peak> leave_out) {
  PsdTerms out;
  const double tau0 = 1 / p.rate_hz;
  const double bin = p.segment ? p.rate_hz / static_cast<double>(p.segment) : 0;
  const auto near_a_peak = [&](double fr) {
    return std::any_of(leave_out.begin(), leave_out.end(),
                       [&](const Peak& k) { return std::fabs(fr - k.f_hz) <= 3.5 * bin; });
  };
  std::vector<double> f, y;
  for (std::size_t i = 0; i < p.f_hz.size(); ++i)
    if (p.f_hz[i] >= f_lo && p.f_hz[i] <= f_hi && p.f_hz[i] > 0 && p.psd[i] > 0) {
      if (near_a_peak(p.f_hz[i])) {
        ++out.left_out;
        continue;
      }
      f.push_back(p.f_hz[i]), y.push_back(p.psd[i]);
    }
  out.bins = f.size();
  if (f.size() < 5) return out;
  // In units where the median bin is near 1 (an even power of two, exact, and the terms scaled
  // back): the weighted columns' norms under- or overflowed in 1e-80 g and 1e90 g (a review), and a
  // unit that is a power of two now gives the same fit bit for bit.
  int e = median_exponent(y);
  e -= e % 2;  // even: the terms are square roots
  for (double& v : y) v = std::ldexp(v, -e);
  auto basis = [&](int k, double fr) {
    switch (k) {
      case 0: return 8 * std::pow(std::sin(std::numbers::pi * fr * tau0), 2) / tau0;
      case 1: return 2.0;
      case 2: return 1 / (std::numbers::pi * fr);
      default: return 1 / (2 * std::numbers::pi * std::numbers::pi * fr * fr);
    }
  };
  const auto n = static_cast<Eigen::Index>(f.size());
  Eigen::MatrixXd X(n, 4);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int k = 0; k < 4; ++k) X(i, k) = basis(k, f[static_cast<std::size_t>(i)]);
  Eigen::VectorXd yv = Eigen::Map<const Eigen::VectorXd>(y.data(), n);
  Eigen::VectorXd mu = yv, theta = Eigen::VectorXd::Zero(4);
  for (int it = 0; it < 6; ++it) {
    const Eigen::VectorXd w = mu.cwiseInverse();
    const Eigen::MatrixXd Xw = w.asDiagonal() * X;
    const Eigen::VectorXd yw = w.cwiseProduct(yv);
    double best = std::numeric_limits<double>::infinity();
    Eigen::VectorXd best_th = Eigen::VectorXd::Zero(4);
    for (int mask = 1; mask < 16; ++mask) {
      std::vector<int> cols;
      for (int k = 0; k < 4; ++k)
        if (mask & (1 << k)) cols.push_back(k);
      Eigen::MatrixXd A(n, static_cast<Eigen::Index>(cols.size()));
      for (std::size_t c = 0; c < cols.size(); ++c) A.col(static_cast<Eigen::Index>(c)) = Xw.col(cols[c]);
      const Eigen::VectorXd sc = A.colwise().norm().transpose();
      if ((sc.array() <= 0).any()) continue;
      const Eigen::MatrixXd An = A * sc.cwiseInverse().asDiagonal();
      const auto qr = An.colPivHouseholderQr();
      if (qr.rank() < static_cast<Eigen::Index>(cols.size())) continue;
      const Eigen::VectorXd t = qr.solve(yw).cwiseQuotient(sc);
      if ((t.array() < 0).any()) continue;
      const double rss = (A * t - yw).squaredNorm();
      if (rss < best) {
        best = rss;
        best_th.setZero();
        for (std::size_t c = 0; c < cols.size(); ++c) best_th(cols[c]) = t(static_cast<Eigen::Index>(c));
      }
    }
    if (!std::isfinite(best)) return out;
    theta = best_th;
    mu = X * theta;
    if ((mu.array() <= 0).any()) return out;
  }
  out.ok = true;
  out.Q = std::ldexp(std::sqrt(theta(0)), e / 2);
  out.N = std::ldexp(std::sqrt(theta(1)), e / 2);
  out.B = std::ldexp(std::sqrt(theta(2)), e / 2);
  out.K = std::ldexp(std::sqrt(theta(3)), e / 2);
  return out;
}

}  // namespace rig::analysis
