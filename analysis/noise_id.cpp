#include "analysis/noise_id.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace rig::analysis {

// Eight fixed partial sums per reduction (lane t % 8, added in a fixed order): vectorised, and
// the result does not depend on the machine or the thread that runs it.
double lag1_acf(std::span<const double> x) {
  const std::size_t n = x.size();
  if (n < 2) return 0;
  constexpr std::size_t L = 8;
  double s[L] = {};
  std::size_t i = 0;
  for (; i + L <= n; i += L)
    for (std::size_t l = 0; l < L; ++l) s[l] += x[i + l];
  double mu = 0;
  for (std::size_t l = 0; l < L; ++l) mu += s[l];
  for (; i < n; ++i) mu += x[i];
  mu /= static_cast<double>(n);
  // a = sum (x_i - mu)(x_{i+1} - mu) over i < n-1, b = sum (x_i - mu)^2: one pass.
  double a[L] = {}, b[L] = {};
  i = 0;
  for (; i + L + 1 <= n; i += L)
    for (std::size_t l = 0; l < L; ++l) {
      const double u = x[i + l] - mu, v = x[i + l + 1] - mu;
      a[l] += u * v;
      b[l] += u * u;
    }
  double sa = 0, sb = 0;
  for (std::size_t l = 0; l < L; ++l) sa += a[l], sb += b[l];
  for (; i + 1 < n; ++i) sa += (x[i] - mu) * (x[i + 1] - mu), sb += (x[i] - mu) * (x[i] - mu);
  sb += (x[n - 1] - mu) * (x[n - 1] - mu);
  return sb > 0 ? sa / sb : 0;
}

NoiseId acf_noise_id(std::span<const double> series, bool phase, int dmax) {
  // No detrending: SP 1065 5.6 leaves deterministic terms to preprocessing, and a linear
  // (frequency) or quadratic (phase) detrend here disagrees with Stable32 on the pink and
  // OCXO tables. r1 is scaled by (N-1)/N, as Stable32 does (reproduced by allantoolkit's
  // acf(); without it pink ADEV AF 218/280 and OCXO AF 113/463 disagree).
  // The series is read in place; a copy is made only when it must be differenced (most taus
  // stop at d = 0, and the copy of up to 2^17 values was a tenth of the identification's time).
  std::vector<double> x;
  NoiseId id;
  for (int d = 0;; ++d) {
    const std::span<const double> cur = d == 0 ? series : std::span<const double>(x);
    const double n = static_cast<double>(cur.size());
    const double r1 = lag1_acf(cur) * (n - 1) / n;
    const double rho = r1 / (1 + r1);
    if (rho < 0.25 || d >= dmax) {
      const int add = phase ? 2 : 0;
      id.rho = rho;
      id.d = d;
      id.alpha_f = -2 * (rho + d) + add;
      id.alpha = static_cast<int>(-std::nearbyint(2 * rho)) - 2 * d + add;  // round half to even, as Stable32/NumPy
      id.acf = true;
      return id;
    }
    if (d == 0) x.assign(series.begin(), series.end());
    for (std::size_t i = 0; i + 1 < x.size(); ++i) x[i] = x[i + 1] - x[i];
    x.pop_back();
  }
}

double b1_theory(double n, int mu) {
  switch (mu) {
    case 2: return n * (n + 1) / 6;
    case 1: return n / 2;
    case 0: return n * std::log(n) / (2 * (n - 1) * std::log(2.0));
    case -1: return 1;
    case -2: return (n * n - 1) / (1.5 * n * (n - 1));
    default: return n * (1 - std::pow(n, mu)) / (2 * (n - 1) * (1 - std::pow(2.0, mu)));
  }
}

double rn_theory(std::size_t m, int alpha) {
  const double af = static_cast<double>(m);
  if (alpha == 2) return 1 / af;
  if (alpha == 1) {  // flicker PM with f_h = 1/(2 tau0) (IEEE 1139)
    const double pi = std::numbers::pi;
    const double avar = (1.038 + 3 * std::log(2 * pi * 0.5 * af)) / (4 * pi * pi);
    const double mvar = 3 * std::log(256.0 / 27.0) / (8 * pi * pi);
    return mvar / avar;
  }
  return 1;
}

namespace {

double nonoverlapped_avar(std::span<const double> z) {
  double s = 0;
  for (std::size_t k = 0; k + 1 < z.size(); ++k) s += (z[k + 1] - z[k]) * (z[k + 1] - z[k]);
  return s / (2 * static_cast<double>(z.size() - 1));
}

}  // namespace

double b1_ratio(std::span<const double> z) {
  if (z.size() < 2) return 1;
  double mu = 0;
  for (double v : z) mu += v;
  mu /= static_cast<double>(z.size());
  double s = 0;
  for (double v : z) s += (v - mu) * (v - mu);
  const double avar = nonoverlapped_avar(z);
  return avar > 0 ? s / static_cast<double>(z.size() - 1) / avar : 1;
}

int b1_mu(double b1, double n) {
  if (!(n > 1)) return -1;  // B1(N, mu) needs N >= 2; white FM, whose B1 is 1 for any N
  for (int mu = 2; mu > -2; --mu)
    if (b1 > std::sqrt(b1_theory(n, mu) * b1_theory(n, mu - 1))) return mu;
  return -2;
}

NoiseId b1_rn_noise_id(std::span<const double> z, const B1Rules& r, const std::function<double()>& mod_avar) {
  NoiseId id;
  id.acf = false;
  // Stable32 identifies only up to half its largest factor (stop ratio, allan.hpp max_factor)
  // and repeats the last alpha beyond: every all-tau table shows it (e.g. PHASE.DAT ADEV
  // repeats AF 99's alpha from AF 101 on, OADEV AF 125's from AF 127 on).
  if ((r.previous && 2 * r.m > r.max_factor) || z.size() < 2) {
    id.alpha = r.previous.value_or(0);  // too few averages and nothing to repeat: white FM
    id.alpha_f = id.alpha;
    return id;
  }
  // B1 = sample variance / non-overlapped AVAR of the plain averages (no detrending: with it
  // OCXO and Cs5071A disagree), tested against B1(N, mu) with N = the deviation's term count,
  // not the number of averages: that is what Stable32's tables follow (OADEV/MDEV/TOTDEV rows
  // of Cs5071A and OCXO, HDEV rows with N = M - 2). SP 1065 5.6; Howe, Beard, Greenhall,
  // Riley, PTTI 2000, tables 3-4.
  const double n = static_cast<double>(r.n_terms);
  int mu = b1_mu(b1_ratio(z), n);
  if (r.hadamard && mu >= 1 && z.size() >= 3) {
    // SP 1065 5.6: for the Hadamard variance the B1 ratio of the frequency differences, mu + 2,
    // reaches random-run FM (Cs5071A HDEV AF 53297: alpha -4). It only refines RW/FW FM: OCXO
    // HDEV AF 1884, where the differences read as PM, stays RW FM.
    std::vector<double> dz(z.size() - 1);
    for (std::size_t i = 0; i + 1 < z.size(); ++i) dz[i] = z[i + 1] - z[i];
    mu = std::clamp(b1_mu(b1_ratio(dz), n) + 2, 1, 3);
  }
  if (mu > -2) {
    id.alpha = -mu - 1;  // mu 3..-1 -> alpha -4..0
  } else if (mod_avar) {
    // PM: R(n) = Mod AVAR / AVAR tells white from flicker PM; Stable32 evaluates it for the
    // modified deviations only (applied to ADEV it would flip Keysight AF 1913 and 2054).
    const double avar = nonoverlapped_avar(z), mvar = mod_avar();
    id.alpha = (mvar >= 0 && avar > 0 && mvar / avar <= std::sqrt(rn_theory(r.m, 2) * rn_theory(r.m, 1))) ? 2 : 1;
  } else {
    id.alpha = 1;  // B1 cannot split PM; Stable32 prints flicker PM
  }
  id.alpha_f = id.alpha;
  return id;
}

}  // namespace rig::analysis
