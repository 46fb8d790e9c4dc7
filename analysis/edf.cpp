#include "analysis/edf.hpp"

#include <array>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/special_functions/binomial.hpp>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rig::analysis {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Greenhall 2003 eq. (7): generalized autocovariance of the noise, by alpha.
double sw(double t, int alpha) {
  const double at = std::abs(t);
  switch (alpha) {
    case 2: return -at;
    case 1: return t == 0 ? 0 : t * t * std::log(at);
    case 0: return at * at * at;
    case -1: return t == 0 ? 0 : std::pow(t, 4) * std::log(at);
    case -2: return std::pow(at, 5);
    case -3: return t == 0 ? 0 : std::pow(t, 6) * std::log(at);
    case -4: return std::pow(at, 7);
    default: throw std::invalid_argument("edf: alpha " + std::to_string(alpha) + " outside -4..2");
  }
}

// eq. (8): the filter's effect on phase (F = inf: no averaging filter).
double sx(double t, double F, int alpha) {
  if (F == kInf) return sw(t, alpha + 2);
  return F * F * (2 * sw(t, alpha) - sw(t - 1.0 / F, alpha) - sw(t + 1.0 / F, alpha));
}

// eq. (9): the d-th difference (binomial weights).
double sz(double t, double F, int alpha, int d) {
  switch (d) {
    case 1: return 2 * sx(t, F, alpha) - sx(t - 1, F, alpha) - sx(t + 1, F, alpha);
    case 2:
      return 6 * sx(t, F, alpha) - 4 * sx(t - 1, F, alpha) - 4 * sx(t + 1, F, alpha) + sx(t - 2, F, alpha) +
             sx(t + 2, F, alpha);
    case 3:
      return 20 * sx(t, F, alpha) - 15 * sx(t - 1, F, alpha) - 15 * sx(t + 1, F, alpha) + 6 * sx(t - 2, F, alpha) +
             6 * sx(t + 2, F, alpha) - sx(t - 3, F, alpha) - sx(t + 3, F, alpha);
    default: throw std::invalid_argument("edf: d must be 1..3");
  }
}

// eq. (10): the basic sum.
double basic_sum(double J, double M, double S, double F, int alpha, int d) {
  double s = std::pow(sz(0, F, alpha, d), 2);
  s += (1 - J / M) * std::pow(sz(J / S, F, alpha, d), 2);
  for (int j = 1; j < static_cast<int>(J); ++j) s += 2 * (1 - j / M) * std::pow(sz(j / S, F, alpha, d), 2);
  return s;
}

struct A01 {
  double a0, a1;
};

// Table 1 (modified variances), rows alpha = 2..-4, columns d = 1..3.
A01 table1(int alpha, int d) {
  static const A01 t[7][3] = {{{2.0 / 3, 1.0 / 3}, {7.0 / 9, 0.5}, {22.0 / 25, 2.0 / 3}},
                              {{0.840, 0.345}, {0.997, 0.616}, {1.141, 0.843}},
                              {{1.079, 0.368}, {1.033, 0.607}, {1.184, 0.848}},
                              {{-1, -1}, {1.048, 0.534}, {1.180, 0.816}},
                              {{-1, -1}, {1.302, 0.535}, {1.175, 0.777}},
                              {{-1, -1}, {-1, -1}, {1.194, 0.703}},
                              {{-1, -1}, {-1, -1}, {1.489, 0.702}}};
  return t[2 - alpha][d - 1];
}

// Table 2 (unmodified variances).
A01 table2(int alpha, int d) {
  static const A01 t[7][3] = {{{1.5, 0.5}, {35.0 / 18, 1.0}, {231.0 / 100, 1.5}},
                              {{78.6, 25.2}, {790.0, 410.0}, {9950.0, 6520.0}},
                              {{2.0 / 3, 1.0 / 6}, {2.0 / 3, 1.0 / 3}, {7.0 / 9, 0.5}},
                              {{-1, -1}, {0.852, 0.375}, {0.997, 0.617}},
                              {{-1, -1}, {1.079, 0.368}, {1.033, 0.607}},
                              {{-1, -1}, {-1, -1}, {1.053, 0.553}},
                              {{-1, -1}, {-1, -1}, {1.302, 0.535}}};
  return t[2 - alpha][d - 1];
}

// Table 3 (alpha = 1, unmodified).
A01 table3(int d) {
  static const A01 t[3] = {{6.0, 4.0}, {15.23, 12.0}, {47.8, 40.0}};
  return t[d - 1];
}

}  // namespace

double edf_greenhall(int alpha, int d, std::size_t m_in, std::size_t n_phase, bool overlapping, bool modified) {
  if (alpha + 2 * d <= 1)
    throw std::invalid_argument("edf_greenhall: alpha " + std::to_string(alpha) + " invalid for d=" + std::to_string(d));
  const double m = static_cast<double>(m_in);
  const double N = static_cast<double>(n_phase);
  const double F = modified ? 1.0 : m;  // filter factor
  const double S = overlapping ? m : 1.0;  // stride factor
  const double L = m / F + m * d;          // filter length on the phase samples
  const double M = 1 + std::floor(S * (N - L) / m);
  const double J = std::min(M, (d + 1) * S);
  constexpr double Jmax = 100;
  const double r = M / S;

  if (modified) {  // case 1: modified variances, all alpha
    if (J <= Jmax) return 1.0 / (basic_sum(J, M, S, 1, alpha, d) / (std::pow(sz(0, 1, alpha, d), 2) * M));
    if (r > d + 1) {
      const A01 a = table1(alpha, d);
      return 1.0 / ((1.0 / r) * (a.a0 - a.a1 / r));
    }
    const double mp = Jmax / r;
    return 1.0 / (basic_sum(Jmax, Jmax, mp, 1, alpha, d) / (std::pow(sz(0, F, alpha, d), 2) * Jmax));
  }
  if (alpha <= 0) {  // case 2: unmodified, alpha <= 0
    if (J <= Jmax) {
      const double mp = (m * (d + 1) <= Jmax) ? m : kInf;
      return 1.0 / (basic_sum(J, M, S, mp, alpha, d) / (std::pow(sz(0, mp, alpha, d), 2) * M));
    }
    if (r > d + 1) {
      const A01 a = table2(alpha, d);
      return 1.0 / ((1.0 / r) * (a.a0 - a.a1 / r));
    }
    const double mp = Jmax / r;
    return 1.0 / (basic_sum(Jmax, Jmax, mp, kInf, alpha, d) / (std::pow(sz(0, kInf, alpha, d), 2) * Jmax));
  }
  if (alpha == 1) {  // case 3: flicker PM
    if (J <= Jmax)
      return 1.0 / (basic_sum(J, M, S, m, 1, d) / (std::pow(sz(0, m, 1, d), 2) * M));
    const A01 b = table3(d);
    if (r > d + 1) {
      const A01 a = table2(alpha, d);
      return 1.0 / ((a.a0 - a.a1 / r) / (std::pow(b.a0 + b.a1 * std::log(m), 2) * r));
    }
    const double mp = Jmax / r;
    return 1.0 / (basic_sum(Jmax, Jmax, mp, mp, 1, d) / (std::pow(b.a0 + b.a1 * std::log(m), 2) * Jmax));
  }
  // case 4: white PM (alpha = 2)
  const double K = std::ceil(r);
  if (K <= d) {
    // Greenhall eq. (12) needs the exact sum for K <= d; use the basic sum with F = m.
    return 1.0 / (basic_sum(J, M, S, m, 2, d) / (std::pow(sz(0, m, 2, d), 2) * M));
  }
  const double a0 = boost::math::binomial_coefficient<double>(4 * d, 2 * d) /
                    std::pow(boost::math::binomial_coefficient<double>(2 * d, d), 2);
  const double a1 = d / 2.0;
  return 1.0 / ((1.0 / M) * (a0 - a1 / r));
}

double edf_simple(std::size_t n_phase, std::size_t m_in, int alpha) {
  const double N = static_cast<double>(n_phase), m = static_cast<double>(m_in);
  switch (alpha) {  // NIST SP 1065 Table 5
    case 2: return (N + 1) * (N - 2 * m) / (2 * (N - m));
    case 1: {
      const double a = (N - 1) / (2 * m), b = (2 * m + 1) * (N - 1) / 4;
      return std::exp(std::sqrt(std::log(a) * std::log(b)));
    }
    case 0: return ((3 * (N - 1) / (2 * m)) - (2 * (N - 2) / N)) * ((4 * m * m) / ((4 * m * m) + 5));
    case -1: return m_in == 1 ? 2 * (N - 2) / (2.3 * N - 4.9) : 5 * N * N / (4 * m * (N + 3 * m));
    case -2: return (N - 2) / (m * (N - 3) * (N - 3)) * ((N - 1) * (N - 1) - 3 * m * (N - 1) + 4 * m * m);
    default: return N - 1;
  }
}

double edf_totdev(std::size_t n_phase, std::size_t m, int alpha) {
  static constexpr std::array<A01, 3> t7 = {{{1.50, 0.0}, {1.17, 0.22}, {0.93, 0.36}}};  // alpha 0, -1, -2
  // Table 7 is for the FM noises; for white and flicker PM, SP 1065 gives TOTDEV no EDF of its own
  // and Table 5's simple AVAR forms stand in.
  const double table = alpha <= 0 && alpha >= -2
                           ? t7[static_cast<std::size_t>(-alpha)].a0 * (static_cast<double>(n_phase) / static_cast<double>(m)) -
                                 t7[static_cast<std::size_t>(-alpha)].a1
                           : edf_simple(n_phase, m, alpha);
  // At m = 1 TOTDEV is OADEV (its N - 2 second differences never reach the reflected extension)
  // and at small m nearly so, while Table 7's fit, made for the long taus TOTDEV is for, gives
  // about twice OADEV's EDF there: its 68 % bounds held the truth on 50 % of white-FM records at
  // m = 1 and 60 % at m = 2 (a metrologist's review, 200 seeds). So the EDF is at most OADEV's
  // (Greenhall) times TOTDEV's share of terms, (N - 2) / (N - 2m): OADEV's at m = 1, Table 7's
  // from about m = 16 on. The cap holds for PM too: Table 5's flicker-PM form gave 1.6x it, bounds
  // narrower than OADEV's at the same tau (a second review). Stable32 uses Table 7 alone
  // (docs/analysis.md).
  if (n_phase > 2 * m && n_phase > 2) {
    const double n = static_cast<double>(n_phase), mm = static_cast<double>(m);
    return std::min(table, edf_greenhall(alpha, 2, m, n_phase, true, false) * (n - 2) / (n - 2 * mm));
  }
  return table;
}

std::pair<double, double> chi2_bounds(double dev, double edf, double confidence) {
  if (!(edf > 0) || !std::isfinite(edf) || !(confidence > 0 && confidence < 1)) return {0.0, 0.0};
  boost::math::chi_squared dist(edf);
  const double pl = (1 - confidence) / 2;
  const double chi_lo = boost::math::quantile(dist, pl);
  const double chi_hi = boost::math::quantile(dist, 1 - pl);
  return {dev * std::sqrt(edf / chi_hi), dev * std::sqrt(edf / chi_lo)};
}

}  // namespace rig::analysis
