#include "analysis/noise_model.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <bit>
#include <optional>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/special_functions/digamma.hpp>
#include <cmath>
#include <limits>
#include <numbers>
#include <thread>
#include <utility>

#include "analysis/edf.hpp"
#include "analysis/median.hpp"
#include "analysis/parallel.hpp"

namespace rig::analysis {

double noise_basis(int k, double tau) {
  switch (k) {
    case 0: return 3 / (tau * tau);
    case 1: return 1 / tau;
    case 2: return 2 * std::numbers::ln2 / std::numbers::pi;
    case 3: return tau / 3;
    default: return tau * tau / 2;
  }
}

std::array<double, 5> term_sigma2(const std::array<double, 5>& theta, double tau) {
  std::array<double, 5> mu{};
  for (int k = 0; k < 5; ++k) mu[static_cast<std::size_t>(k)] = theta[static_cast<std::size_t>(k)] * noise_basis(k, tau);
  return mu;
}

double model_sigma2(const std::array<double, 5>& theta, double tau) {
  double mu = 0;
  for (int k = 0; k < 5; ++k) mu += theta[static_cast<std::size_t>(k)] * noise_basis(k, tau);
  return mu;
}

std::array<double, 4> random_term_factors(std::size_t m, std::size_t n_phase) {
  static const int kAlpha[4] = {2, 0, -1, -2};
  std::array<double, 4> f{};
  for (std::size_t k = 0; k < 4; ++k) f[k] = std::sqrt(2 / edf_greenhall(kAlpha[k], 2, m, n_phase, true, false));
  return f;
}

std::array<double, 5> term_scatter(const std::array<double, 5>& mu, const std::array<double, 4>& factors, std::size_t m,
                                   std::size_t n_phase) {
  std::array<double, 5> sd{};
  for (std::size_t k = 0; k < 4; ++k)
    if (mu[k] > 0) sd[k] = mu[k] * factors[k];
  if (mu[4] > 0 && n_phase > 2 * m + 1) {
    // The ramp's second differences are one constant d (mu_R = d^2/2), so s = mu_R + d ebar +
    // s_random, and its only scatter is the cross term d ebar: var = 2 mu_R var(ebar), ebar the
    // mean of the M = N - 2m random second differences over tau. The sum telescopes: M ebar =
    // sum_{j<m} (ybar_{M+j} - ybar_j) (ybar_i the m-average of the frequency from sample i), so
    // ebar = (m/M) (A_end - A_start), A the triangular-weighted means of the frequency over the
    // record's first and last 2m samples, M apart. V = var(A_end - A_start) per term, in units of
    // its own Allan variance mu_k at m:
    //   Q (white PM): M ebar tau = a sum of 4m independent phases: var(ebar) = (4/3) mu_Q m / M^2;
    //   N (white FM): var(A) = (2/3) sigma_y^2 / m each, independent: V = (4/3) mu_N;
    //   B (flicker FM): V = 2 mu_B at lag m (adjacent averages), growing with ln(lag):
    //       V ~ 2 mu_B (1 + log2(M/m)/2) (approximate: flicker's structure function);
    //   K (random-walk FM, K^2 tau0 = 3 mu_K/m per sample): V = K^2 tau0 (M - 0.46 m), 0.46 m
    //       the mean |s - t| of two triangular weights of width 2m.
    // The cross term is uncorrelated with s_random (odd moments of Gaussian noise vanish).
    const double dm = static_cast<double>(m), M = static_cast<double>(n_phase - 1 - 2 * m) + 1;
    const double r = dm / M;
    const double var_ebar = 4.0 / 3 * mu[0] * dm / (M * M) + r * r * (4.0 / 3 * mu[1] + 2 * mu[2] * (1 + std::log2(std::max(1.0, M / dm)) / 2) +
                                                                  3 * mu[3] * std::max(0.0, M - 0.46 * dm) / dm);
    sd[4] = std::sqrt(2 * mu[4] * var_ebar);
  }
  return sd;
}

std::array<double, 5> term_scatter(const std::array<double, 5>& mu, std::size_t m, std::size_t n_phase) {
  return term_scatter(mu, random_term_factors(m, n_phase), m, n_phase);
}

double model_edf(const std::array<double, 5>& mu, const std::array<double, 4>& factors, std::size_t m, std::size_t n_phase) {
  double total = 0, sd_random = 0;
  for (std::size_t k = 0; k < 5; ++k) total += mu[k];
  if (!(total > 0)) return edf_greenhall(0, 2, m, n_phase, true, false);  // no noise: white FM's
  // On the terms' shares: the EDF has no unit, and total^2 of a variance in 1e90 g overflowed (a
  // review: the paper B's EDF was null and its interval [0, 0] there).
  std::array<double, 5> share{};
  for (std::size_t k = 0; k < 5; ++k) share[k] = mu[k] / total;
  const std::array<double, 5> sd = term_scatter(share, factors, m, n_phase);
  for (std::size_t k = 0; k < 4; ++k) sd_random += sd[k];
  const double var = sd_random * sd_random + sd[4] * sd[4];
  if (!(var > 0)) return edf_greenhall(0, 2, m, n_phase, true, false);  // nothing random: white FM's
  return 2 / var;
}

double model_edf(const std::array<double, 5>& mu, std::size_t m, std::size_t n_phase) {
  return model_edf(mu, random_term_factors(m, n_phase), m, n_phase);
}

namespace {

// random_term_factors at each of the factors m on a record of n_phase points.
std::vector<std::array<double, 4>> factors_at(const std::vector<std::size_t>& m, std::size_t n_phase) {
  std::vector<std::array<double, 4>> out(m.size());
  for (std::size_t i = 0; i < m.size(); ++i) out[i] = random_term_factors(m[i], n_phase);
  return out;
}

// The Allan points a fit reads. The points and their factors are fixed when built, so factors
// always belong to m (built here from m, or sliced with it by tail); the fit sets nu alone.
struct Pts {
  Pts(std::vector<double> tau_s, std::vector<double> sigma2, std::vector<std::size_t> factor_m, std::size_t n_phase)
      : tau(std::move(tau_s)), s(std::move(sigma2)), m(std::move(factor_m)), factors(factors_at(m, n_phase)),
        nu(tau.size()) {}

  // Points 0..count, each with its factors.
  Pts head(std::size_t count) const {
    const auto at = static_cast<std::ptrdiff_t>(count);
    return Pts({tau.begin(), tau.begin() + at}, {s.begin(), s.begin() + at}, {m.begin(), m.begin() + at},
               {factors.begin(), factors.begin() + at});
  }
  // Points from..end, each with its factors.
  Pts tail(std::size_t from) const {
    const auto at = static_cast<std::ptrdiff_t>(from);
    return Pts({tau.begin() + at, tau.end()}, {s.begin() + at, s.end()}, {m.begin() + at, m.end()},
               {factors.begin() + at, factors.end()});
  }

  const std::vector<double> tau, s;  // tau, measured sigma^2
  const std::vector<std::size_t> m;
  // random_term_factors at each point: they depend on (m, n_phase) alone, while the fit evaluates
  // the model's EDF and covariance some thousand times (each a Greenhall sum per term: a fifth
  // of the fit's instructions before they were kept here).
  const std::vector<std::array<double, 4>> factors;
  std::vector<double> nu;  // EDF in use, one per point

 private:
  Pts(std::vector<double> tau_s, std::vector<double> sigma2, std::vector<std::size_t> factor_m,
      std::vector<std::array<double, 4>> kept)
      : tau(std::move(tau_s)), s(std::move(sigma2)), m(std::move(factor_m)), factors(std::move(kept)), nu(tau.size()) {}
};

struct SubsetFit {
  bool ok = false;
  int mask = 0, k = 0;
  std::array<double, 5> theta{};
  Eigen::MatrixXd cov;  // over the subset's columns, in order
  double nll = std::numeric_limits<double>::infinity();
};

double nll_of(const Pts& p, const std::array<double, 5>& th) {
  double l = 0;
  for (std::size_t i = 0; i < p.tau.size(); ++i) {
    const double mu = model_sigma2(th, p.tau[i]);
    if (!(mu > 0)) return std::numeric_limits<double>::infinity();
    l += p.nu[i] / 2 * (p.s[i] / mu + std::log(mu));
  }
  return l;
}

// The terms (0..4: Q, N, B, K, R) whose bits are set in `mask`, in order.
std::vector<int> columns_of(int mask) {
  std::vector<int> cols;
  for (int k = 0; k < 5; ++k)
    if (mask & (1 << k)) cols.push_back(k);
  return cols;
}

// Maximum likelihood of the terms in `mask` for s_i ~ mu_i chi2(nu_i)/nu_i: the Gamma GLM with
// identity link, by iteratively reweighted least squares (weights nu_i / (2 mu_i^2); the score
// equations sum nu_i b_ij (s_i - mu_i) / mu_i^2 = 0 are the likelihood's). The covariance is the
// inverse Fisher information sum nu_i b_i b_i^T / (2 mu_i^2). nonneg: reject a negative theta.
SubsetFit fit_subset(const Pts& p, int mask, bool nonneg) {
  SubsetFit f;
  f.mask = mask;
  const std::vector<int> cols = columns_of(mask);
  f.k = static_cast<int>(cols.size());
  const auto n = static_cast<Eigen::Index>(p.tau.size()), c = static_cast<Eigen::Index>(cols.size());
  if (c == 0 || c > n) return f;
  Eigen::MatrixXd X(n, c);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < c; ++j) X(i, j) = noise_basis(cols[static_cast<std::size_t>(j)], p.tau[static_cast<std::size_t>(i)]);
  Eigen::VectorXd mu(n), y(n);
  for (Eigen::Index i = 0; i < n; ++i) mu(i) = y(i) = p.s[static_cast<std::size_t>(i)];
  Eigen::VectorXd th = Eigen::VectorXd::Zero(c);
  Eigen::MatrixXd info(c, c);
  // Buffers made once, and sqrt(nu_i / 2) and X * theta of an accepted step kept: the same
  // expressions on the same operands as when each iteration made its own (the same bits).
  Eigen::VectorXd root_half_nu(n), w(n), scale(c), next(c), mu_next(n);
  for (Eigen::Index i = 0; i < n; ++i) root_half_nu(i) = std::sqrt(p.nu[static_cast<std::size_t>(i)] / 2);
  Eigen::MatrixXd Xw(n, c), Xn(n, c);
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(n, c);
  // w = sqrt(nu/2) / mu, Xw = diag(w) X, scale its column norms, Xn = Xw with unit columns.
  const auto weigh = [&] {
    w = root_half_nu.cwiseQuotient(mu);
    Xw = w.asDiagonal() * X;
    scale = Xw.colwise().norm().transpose();
    Xn = Xw * scale.cwiseInverse().asDiagonal();
  };
  for (int it = 0; it < 50; ++it) {
    weigh();
    if ((scale.array() <= 0).any()) return f;
    qr.compute(Xn);
    if (qr.rank() < c) return f;
    next = qr.solve(w.cwiseProduct(y)).cwiseQuotient(scale);
    mu_next.noalias() = X * next;
    if ((mu_next.array() <= 0).any()) {
      // The step leaves the positive means: halve towards the previous estimate.
      if (it == 0) return f;
      bool fixed = false;
      Eigen::VectorXd t2 = next;
      for (int h = 0; h < 30 && !fixed; ++h) {
        t2 = (t2 + th) / 2;
        fixed = ((X * t2).array() > 0).all();
      }
      if (!fixed) return f;
      th = t2;
      mu.noalias() = X * th;
    } else {
      const double change = (next - th).cwiseAbs().cwiseQuotient(next.cwiseAbs().cwiseMax(1e-300)).maxCoeff();
      th.swap(next);
      mu.swap(mu_next);  // X * th
      if (change < 1e-10) break;
    }
  }
  for (Eigen::Index j = 0; j < c; ++j) f.theta[static_cast<std::size_t>(cols[static_cast<std::size_t>(j)])] = th(j);
  if (nonneg && (th.array() < 0).any()) return f;
  weigh();
  info = Xn.transpose() * Xn;
  f.cov = scale.cwiseInverse().asDiagonal() * info.inverse() * scale.cwiseInverse().asDiagonal();
  f.nll = nll_of(p, f.theta);
  f.ok = std::isfinite(f.nll);
  return f;
}

// AICc = 2 nll + 2k + 2k(k+1)/(n-k-1) (Hurvich & Tsai 1989); n-k-1 <= 0: the subset is too large.
double aicc(const SubsetFit& f, std::size_t n) {
  const double k = f.k, dn = static_cast<double>(n);
  if (dn - k - 1 <= 0) return std::numeric_limits<double>::infinity();
  return 2 * f.nll + 2 * k + 2 * k * (k + 1) / (dn - k - 1);
}

double sd_of(const SubsetFit& f, int term) {
  int j = 0;
  for (int k = 0; k < term; ++k)
    if (f.mask & (1 << k)) ++j;
  return std::sqrt(std::max(0.0, f.cov(j, j)));
}


// Correlation of ln(OADEV^2) at factors m and 2^L m for one power law, L = 1..5 octaves apart,
// measured by simulation (NumPy, 400 records of 65536 points per law, m = 4..256, averaged over
// m; tests/analysis/test_noise_coverage.cpp checks the white-FM and random-walk values). White PM
// stays near 0.53 at any distance (every factor's estimate shares sum x_n^2); beyond 5 octaves
// random walk decays by 0.8 per octave, the others are 0. Negative values (flicker, -0.07 at 5)
// are taken as 0.
constexpr double kOctaveCorr[4][5] = {
    {0.41, 0.52, 0.53, 0.54, 0.53},  // white PM (Q)
    {0.51, 0.16, 0.06, 0.02, 0.0},   // white FM (N)
    {0.66, 0.24, 0.04, 0.0, 0.0},    // flicker FM (B)
    {0.88, 0.66, 0.47, 0.35, 0.28},  // random walk FM (K)
};
double octave_corr(int k, int lag) {
  if (lag == 0) return 1;
  if (lag <= 5) return kOctaveCorr[k][lag - 1];
  if (k == 0) return kOctaveCorr[0][4];
  if (k == 3) return kOctaveCorr[3][4] * std::pow(0.8, lag - 5);
  return 0;
}

// (mu_Q + mu_N) / mu at tau: the share of the white (high-frequency) terms in the model; 1 when
// the model has none of the five terms.
double white_share(const std::array<double, 5>& theta, double tau) {
  const std::array<double, 5> mu = term_sigma2(theta, tau);
  double w = 0, all = 0;
  for (std::size_t k = 0; k < 5; ++k) {
    all += mu[k];
    if (k < 2) w += mu[k];
  }
  return all > 0 && w > 0 ? w / all : 1;
}

// Covariance of ln s_i under the model theta: Sigma_ij = C_ij sqrt(v_i v_j) + (delta h_i)^2 [i = j],
// h_i = (mu_Q + mu_N)/mu at tau_i (the model error's profile, see fit_noise_model),
// v_i = 2/nu_i (the variance of s_i/mu_i; ln s_i is taken as normal with it: at the few EDF of
// the longest points the log chi-square's own, psi'(nu/2), is larger, but simulated records
// measure 2/nu there, coverage_noise --covariance, docs/analysis.md);
// C_ij = sum_k w_ik w_jk rho_k(L_ij) / sqrt(sum_k w_ik^2 sum_k w_jk^2) with
// w_ik = term_scatter (each term's share of the scatter; the ramp's cross term correlated as
// random walk's, whose end-to-end differences it mostly is) and L_ij the octaves apart.
Eigen::MatrixXd model_cov(const Pts& p, const std::array<double, 5>& theta, std::size_t n_phase, double delta) {
  const std::size_t n = p.tau.size();
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), 5);
  for (std::size_t i = 0; i < n; ++i) {
    const std::array<double, 5> mu = term_sigma2(theta, p.tau[i]);
    const std::array<double, 5> sd = term_scatter(mu, p.factors[i], p.m[i], n_phase);
    for (int k = 0; k < 5; ++k) w(static_cast<Eigen::Index>(i), k) = sd[static_cast<std::size_t>(k)];
  }
  Eigen::MatrixXd S(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) {
      const auto ii = static_cast<Eigen::Index>(i), jj = static_cast<Eigen::Index>(j);
      const int lag = std::max(1, static_cast<int>(std::lround(std::abs(std::log2(p.tau[j] / p.tau[i])))));
      double c = i == j ? 1 : 0;
      const double ni = w.row(ii).norm(), nj = w.row(jj).norm();
      if (i != j && ni > 0 && nj > 0) {
        c = 0;
        for (int k = 0; k < 5; ++k) c += w(ii, k) * w(jj, k) * octave_corr(std::min(k, 3), lag);
        c /= ni * nj;
      }
      S(ii, jj) = c * std::sqrt(2 / p.nu[i] * 2 / p.nu[j]) + (i == j ? std::pow(delta * white_share(theta, p.tau[i]), 2) : 0);
    }
  return S;
}

// E[ln(chi2_nu / nu)] = digamma(nu/2) - ln(nu/2): the bias of ln s_i.
double log_bias(double nu) { return boost::math::digamma(nu / 2) - std::log(nu / 2); }

// How a point's departure from the model is measured. log: r_i = ln s_i - ln mu_i - bias_i, the
// fit's (normal with variance 2/nu_i to first order). cube_root: the Wilson-Hilferty transform of
// x_i = s_i / mu_i ~ chi2_nu/nu, r_i = 3 (x_i^(1/3) - (1 - 2/(9 nu_i))), normal with variance
// 2/nu_i to within a few per cent in its tails down to nu = 2 (Wilson & Hilferty 1931; Johnson,
// Kotz & Balakrishnan, Continuous Univariate Distributions 1, 18.8), where ln x has a heavy lower
// tail: at nu = 2, x = 0.1 the log residual reads -1.73 sd, the cube root -1.27, the chi-square's
// own quantile -1.31. Scaled by 3 so that both have the same first-order variance and W serves both.
enum class Residual { log, cube_root };

double residual_of(Residual kind, double s, double mu, double nu) {
  if (kind == Residual::log) return std::log(s) - log_bias(nu) - std::log(mu);
  return 3 * (std::cbrt(s / mu) - (1 - 2 / (9 * nu)));
}

// Generalized least squares of the points on mu_i(theta) (residuals of `kind`) with the covariance
// W^-1 (fixed), Gauss-Newton from `start` over the terms in `mask`; cov = (J^T W J)^-1, nll =
// r^T W r / 2. offset: a variance added to every mu_i (a term held fixed), none by default.
SubsetFit gls_subset(const Pts& p, const Eigen::MatrixXd& W, int mask, std::array<double, 5> start, bool nonneg,
                     const Eigen::VectorXd* offset = nullptr, Residual kind = Residual::log) {
  SubsetFit f;
  f.mask = mask;
  const std::vector<int> cols = columns_of(mask);
  f.k = static_cast<int>(cols.size());
  const auto n = static_cast<Eigen::Index>(p.tau.size()), c = static_cast<Eigen::Index>(cols.size());
  if (c == 0 || c > n) return f;
  Eigen::MatrixXd X(n, c);
  Eigen::VectorXd ly(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto si = static_cast<std::size_t>(i);
    for (Eigen::Index j = 0; j < c; ++j) X(i, j) = noise_basis(cols[static_cast<std::size_t>(j)], p.tau[si]);
    if (kind == Residual::log) ly(i) = std::log(p.s[si]) - log_bias(p.nu[si]);  // the cube root needs none
  }
  Eigen::VectorXd th(c);
  for (Eigen::Index j = 0; j < c; ++j) th(j) = start[static_cast<std::size_t>(cols[static_cast<std::size_t>(j)])];
  // The buffers of the loop are made once (a fit runs some ten iterations over a few points:
  // the allocations had cost as much as the arithmetic). Each product below is the same Eigen
  // expression on the same operands as before, so the results are the same bit for bit: mu of
  // the accepted step is kept from the objective instead of being multiplied out again, and
  // Jn^T W, which the normal matrix and its right-hand side both start with, is formed once.
  Eigen::VectorXd mu_try(n), res(n);
  auto objective = [&](const Eigen::VectorXd& t, Eigen::VectorXd& r) {
    mu_try.noalias() = X * t;
    if (offset) mu_try += *offset;
    if ((mu_try.array() <= 0).any()) return std::numeric_limits<double>::infinity();
    if (kind == Residual::log) {
      res = ly - mu_try.array().log().matrix();
    } else {
      for (Eigen::Index i = 0; i < n; ++i) {
        const auto si = static_cast<std::size_t>(i);
        res(i) = residual_of(kind, p.s[si], mu_try(i), p.nu[si]);
      }
    }
    r = res;
    return res.dot(W * res);
  };
  Eigen::VectorXd r(n), rn(n), tn(c), step(c), scale(c), mu(n);
  double F = objective(th, r);
  if (!std::isfinite(F)) return f;
  mu.swap(mu_try);  // X * th
  Eigen::MatrixXd J(n, c), Jn(n, c), JtW(c, n), A(c, c);
  Eigen::LDLT<Eigen::MatrixXd> ldlt(c);
  // Jn = J scaled to unit columns (J = d ln mu / d theta at mu); JtW = Jn^T W; A = Jn^T W Jn.
  const auto normal_matrix = [&] {
    // -d r / d theta: d ln mu / d theta for the log residual, x^(1/3) d ln mu / d theta for the cube root.
    if (kind == Residual::log) {
      J = mu.cwiseInverse().asDiagonal() * X;
    } else {
      Eigen::VectorXd g(n);
      for (Eigen::Index i = 0; i < n; ++i) g(i) = std::cbrt(p.s[static_cast<std::size_t>(i)] / mu(i)) / mu(i);
      J = g.asDiagonal() * X;
    }
    scale = J.colwise().norm().transpose();
    Jn = J * scale.cwiseInverse().asDiagonal();
    JtW = Jn.transpose() * W;
    A = JtW * Jn;
    return !(scale.array() <= 0).any();
  };
  for (int it = 0; it < 100; ++it) {
    if (!normal_matrix()) return f;
    step = ldlt.compute(A).solve(JtW * r).cwiseQuotient(scale);
    double lam = 1, Fn = std::numeric_limits<double>::infinity();
    for (int h = 0; h < 40; ++h, lam /= 2) {
      tn = th + lam * step;
      Fn = objective(tn, rn);
      if (Fn <= F) break;
    }
    if (!(Fn <= F)) break;
    const double gain = F - Fn;
    th.swap(tn), r.swap(rn), mu.swap(mu_try), F = Fn;
    if (gain < 1e-12 * (1 + F)) break;
  }
  for (Eigen::Index j = 0; j < c; ++j) f.theta[static_cast<std::size_t>(cols[static_cast<std::size_t>(j)])] = th(j);
  if (nonneg && (th.array() < 0).any()) return f;
  normal_matrix();  // at th
  f.cov = scale.cwiseInverse().asDiagonal() * A.inverse() * scale.cwiseInverse().asDiagonal();
  f.nll = F / 2;
  f.ok = std::isfinite(f.nll) && f.cov.allFinite();
  return f;
}


using Team = detail::WorkTeam;
constexpr int kSubsets = 31;  // the non-empty subsets of {Q, N, B, K, R}: masks 1..31

// fn(mask) for every subset, over the team; [mask - 1] of the result. Each subset's fit is
// independent of the others', so the thread count does not change any result.
template <class Fn>
std::array<SubsetFit, kSubsets> each_subset(Team& team, Fn fn) {
  std::array<SubsetFit, kSubsets> fits;
  team.run(kSubsets, [&](std::size_t i) { fits[i] = fn(static_cast<int>(i) + 1); });
  return fits;
}

// Every subset by GLS on W, each from its own Gamma-likelihood solution, non-negative; with its
// AICc (infinite where the subset has no non-negative solution). What the selection and the
// plausible models rank.
std::array<std::pair<double, SubsetFit>, kSubsets> gls_every_subset(const Pts& p, const Eigen::MatrixXd& W, Team& team) {
  const std::array<SubsetFit, kSubsets> fits = each_subset(team, [&](int mask) {
    const SubsetFit g = fit_subset(p, mask, true);
    return g.ok ? gls_subset(p, W, mask, g.theta, true) : SubsetFit{};
  });
  std::array<std::pair<double, SubsetFit>, kSubsets> out;
  for (std::size_t i = 0; i < fits.size(); ++i)
    out[i] = {fits[i].ok ? aicc(fits[i], p.tau.size()) : std::numeric_limits<double>::infinity(), fits[i]};
  return out;
}

// The model selected on the points `p` (EDF and covariance from the model, GLS over every subset,
// AICc), with its goodness of fit. allow_error: add the Birge model error delta when the
// selected model's chi2/dof > 1 (the fallback when no tau range is adequate, see fit_noise_model).
struct Selection {
  bool ok = false;
  SubsetFit best;
  Eigen::MatrixXd W;      // the inverse covariance of ln s_i the terms were fitted with
  double delta = 0;       // the model error in W
  double chi2 = 0;        // GLS chi-square of the selected model on its own covariance, delta = 0
  double dof = 1;         // points - terms
  double p_value = 0;     // P(chi2_dof >= chi2)
  double aicc = 0;
  std::string reason;
};

// chi2 of the residuals of `theta` on p (EDF from theta) under the model covariance with error d.
double gls_chi2(const Pts& p, const std::array<double, 5>& theta, std::size_t n_phase, double d) {
  const std::size_t n = p.tau.size();
  Eigen::VectorXd r(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const double mu = model_sigma2(theta, p.tau[i]);
    r(static_cast<Eigen::Index>(i)) = std::log(p.s[i] / mu) - log_bias(p.nu[i]);
  }
  const Eigen::MatrixXd S = model_cov(p, theta, n_phase, d);
  return r.dot(S.ldlt().solve(r));
}

void set_model_edf(Pts& p, const std::array<double, 5>& theta, std::size_t n_phase) {
  for (std::size_t i = 0; i < p.tau.size(); ++i) {
    const std::array<double, 5> mu = term_sigma2(theta, p.tau[i]);
    p.nu[i] = model_edf(mu, p.factors[i], p.m[i], n_phase);
  }
}

Selection select_model(Pts p, std::size_t n_phase, bool allow_error, Team& team) {
  Selection out;
  const std::size_t n = p.tau.size();
  for (std::size_t i = 0; i < n; ++i) p.nu[i] = edf_greenhall(0, 2, p.m[i], n_phase, true, false);  // start: white FM
  // Start: the best subset with independent chi-square points (Gamma likelihood).
  SubsetFit best;
  double best_aic = std::numeric_limits<double>::infinity();
  for (const SubsetFit& f : each_subset(team, [&](int mask) { return fit_subset(p, mask, true); }))
    if (f.ok && aicc(f, n) < best_aic) best_aic = aicc(f, n), best = f;
  if (!best.ok) {
    out.reason = "no non-negative model fits the Allan points";
    return out;
  }
  // Then: EDF and covariance from the model, GLS over every subset, select, repeat.
  for (int iter = 0; iter < 5; ++iter) {
    const int prev_mask = best.mask;
    set_model_edf(p, best.theta, n_phase);
    const double dof = std::max(1.0, static_cast<double>(n) - best.k);
    out.delta = 0;
    // Birge / Paule-Mandel (fallback only): a relative model error so that chi2/dof = 1:
    // var(ln s_i) = 2/nu_i + (delta h_i)^2 with h_i the white terms' (Q, N) share of the model
    // at tau_i: what the five terms miss on a real DUT is high-frequency (tones, folded pick-up,
    // the output filter's shape), falling with tau like Q and N.
    if (allow_error && gls_chi2(p, best.theta, n_phase, 0) / dof > 1) {
      double lo = 0, hi = 0.1;
      while (gls_chi2(p, best.theta, n_phase, hi) / dof > 1 && hi < 10) hi *= 2;
      for (int it = 0; it < 40; ++it) {
        const double mid = (lo + hi) / 2;
        (gls_chi2(p, best.theta, n_phase, mid) / dof > 1 ? lo : hi) = mid;
      }
      out.delta = hi;
    }
    out.W = model_cov(p, best.theta, n_phase, out.delta).inverse();
    SubsetFit sel;
    best_aic = std::numeric_limits<double>::infinity();
    for (const auto& [a, f] : gls_every_subset(p, out.W, team))
      if (f.ok && a < best_aic) best_aic = a, sel = f;
    if (!sel.ok) break;
    best = sel;
    out.aicc = best_aic;
    if (iter > 0 && best.mask == prev_mask) break;
  }
  // Goodness of fit of the selected model on the covariance it implies (no model error).
  set_model_edf(p, best.theta, n_phase);
  out.dof = std::max(1.0, static_cast<double>(n) - best.k);
  out.chi2 = gls_chi2(p, best.theta, n_phase, 0);
  out.p_value = boost::math::cdf(boost::math::complement(boost::math::chi_squared(out.dof), out.chi2));
  out.best = best;
  out.ok = true;
  return out;
}

// The widest non-negative model on the points p: all five terms by GLS with the covariance the
// model implies, constrained to theta >= 0 (NNLS over the subsets); the covariance re-evaluated
// from the result, up to four rounds. No term is left out because AICc would: a term the data cannot tell from zero
// stays in with its (wide) interval instead of landing in its neighbours. W: the inverse
// covariance of the last round.
SubsetFit widest_model(Pts& p, std::size_t n_phase, double delta, std::array<double, 5> start, Eigen::MatrixXd& W,
                       Team& team) {
  SubsetFit f;
  for (int round = 0; round < 4; ++round) {
    set_model_edf(p, start, n_phase);
    W = model_cov(p, start, n_phase, delta).inverse();
    // Non-negative least squares on W: the least chi-square over the subsets whose own GLS
    // solution is non-negative (the constrained optimum is the unconstrained one on its face);
    // of equal chi-squares the larger subset.
    SubsetFit best;
    for (const SubsetFit& g : each_subset(team, [&](int mask) {
           std::array<double, 5> s0 = start;
           for (int k = 0; k < 5; ++k)
             if (!(mask & (1 << k))) s0[static_cast<std::size_t>(k)] = 0;
           return gls_subset(p, W, mask, s0, true);
         }))
      if (g.ok && (!best.ok || g.nll < best.nll * (1 - 1e-9) || (g.nll <= best.nll * (1 + 1e-9) && g.k > best.k))) best = g;
    if (!best.ok) return best;
    f = best;
    start = f.theta;
  }
  return f;
}

// Models the data support about as well as the selected one: every non-negative subset whose
// AICc is within kPlausibleAicc of the least, on the covariance the selected model implies
// (Burnham & Anderson 2002, section 2.6: Delta_i <= 2 has substantial support). Collinear terms
// (K against B + R over tau <= T/4 of one hour) give such alternatives: a bound that holds
// over only one of them excludes what the other reads (issue 12: B 5-7x on a K record).
constexpr double kPlausibleAicc = 2.0;

std::vector<SubsetFit> plausible_models(Pts p, const Selection& sel, std::size_t n_phase, Team& team) {
  set_model_edf(p, sel.best.theta, n_phase);
  const Eigen::MatrixXd W = model_cov(p, sel.best.theta, n_phase, sel.delta).inverse();
  auto fits = gls_every_subset(p, W, team);
  double least = std::numeric_limits<double>::infinity();
  for (const auto& [a, f] : fits)
    if (f.ok) least = std::min(least, a);
  std::vector<SubsetFit> out;
  for (auto& [a, f] : fits)
    if (f.ok && a <= least + kPlausibleAicc) out.push_back(std::move(f));
  return out;
}

// r^T W r of the terms in `mask` fitted (sign free) with term k held at theta_k = u.
double chi2_with_term_at(const Pts& p, const Eigen::MatrixXd& W, int mask, int k, double u,
                         const std::array<double, 5>& start, Residual kind) {
  const auto n = static_cast<Eigen::Index>(p.tau.size());
  Eigen::VectorXd offset(n);
  for (Eigen::Index i = 0; i < n; ++i) offset(i) = u * noise_basis(k, p.tau[static_cast<std::size_t>(i)]);
  if (mask == 0) {
    if ((offset.array() <= 0).any()) return std::numeric_limits<double>::infinity();
    Eigen::VectorXd r(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto si = static_cast<std::size_t>(i);
      r(i) = residual_of(kind, p.s[si], offset(i), p.nu[si]);
    }
    return r.dot(W * r);
  }
  const SubsetFit f = gls_subset(p, W, mask, start, false, &offset, kind);
  return f.ok ? 2 * f.nll : std::numeric_limits<double>::infinity();
}

// The test of theta_k = u against theta_k >= 0 free, both on the covariance and EDFs the model
// implies with theta_k = u: the rise of the chi-square. Evaluating the points' scatter under the
// hypothesis (as a score test does) instead of at the fit is what matters for a term left out:
// fitted without it, the long points of a random walk look like a few-EDF white FM, and the
// interval linearised there (theta + z sd) excluded the truth (below).
double chi2_rise_at(Pts p, const std::array<double, 5>& th_cov, const SubsetFit& best, int k, double u,
                    std::size_t n_phase, double delta, Residual kind) {
  std::array<double, 5> th = th_cov;
  th[static_cast<std::size_t>(k)] = u;
  set_model_edf(p, th, n_phase);
  const Eigen::MatrixXd W = model_cov(p, th, n_phase, delta).inverse();
  const int others = best.mask & ~(1 << k);
  const double at_u = chi2_with_term_at(p, W, others, k, u, best.theta, kind);
  const SubsetFit free = gls_subset(p, W, others | (1 << k), best.theta, false, nullptr, kind);
  const double least = free.ok && free.theta[static_cast<std::size_t>(k)] >= 0
                           ? 2 * free.nll
                           : chi2_with_term_at(p, W, others, k, 0, best.theta, kind);
  return at_u - least;
}

// The upper limit of a term the model leaves out, by inverting that test: the least theta_k
// above `wald` (theta^+ + z sd, the linearised limit) whose chi-square rises by z^2 or more, never
// below `wald`. A metrologist's outside check (white + random walk FM, K dominating the last octave
// or two of a 1000 s record, 100 seeds) had K null on 20 records with the linearised upper limit
// below the truth on 11 of them at 95 % (docs/analysis.md, "Coverage over injected noise").
// The test measures each point on the cube root of s/mu: a null is the records whose long points
// came out low, where the log residual's heavy lower tail rejected the truth (on 1500 records of
// that check the nulls' limits held 69 % at 95 % on ln s, 88 % on the cube root).
double inverted_upper(const Pts& p, const std::array<double, 5>& th_cov, const SubsetFit& best, int k, double z,
                      std::size_t n_phase, double delta, double wald) {
  if (!(wald > 0) || !std::isfinite(wald)) return wald;
  // Without a point to spare beyond the terms fitted with theta_k free, both fits pass through
  // every point and the other terms (free in sign) absorb any theta_k: the test never rejects
  // (a review: 12-30 white-noise values, 3 octave points, N <= 1.4e6 for a truth of 1).
  const int others = best.mask & ~(1 << k);
  if (p.tau.size() < static_cast<std::size_t>(std::popcount(static_cast<unsigned>(others))) + 2) return wald;
  const double z2 = z * z;
  auto rise = [&](double u) { return chi2_rise_at(p, th_cov, best, k, u, n_phase, delta, Residual::cube_root); };
  double lo = wald, hi = wald, r = rise(wald), r_lo = r;
  if (!(r < z2)) return wald;
  for (int i = 0; i < 40 && r < z2; ++i) {
    lo = hi, r_lo = r;
    hi *= 2;
    r = rise(hi);
  }
  // Not rejected even at 2^40 times the linearised limit: the test cannot bound the term on these
  // points (the other terms absorb it), and the linearised limit stands.
  if (r < z2) return wald;
  // Between the last accepted and the first rejected value, on ln theta_k: regula falsi with the
  // Illinois modification (the rise is smooth in theta_k; a few evaluations where halving the
  // factor took twelve) until the two are within 0.01 %; the rejected side is returned.
  double a = std::log(lo), b = std::log(hi), fa = r_lo - z2, fb = r - z2;
  int side = 0;
  for (int i = 0; i < 40 && b - a > 1e-4; ++i) {
    double c = (a * fb - b * fa) / (fb - fa);
    if (!(c > a && c < b)) c = (a + b) / 2;
    const double fc = rise(std::exp(c)) - z2;
    if (fc < 0) {
      a = c, fa = fc;
      if (side == -1) fb /= 2;
      side = -1;
    } else {
      b = c, fb = fc;
      if (side == 1) fa /= 2;
      side = 1;
    }
  }
  return std::exp(b);
}

}  // namespace

std::vector<std::size_t> octave_points(std::span<const DevPoint> oadev) {
  auto usable = [](const DevPoint& d) { return d.dev > 0 && d.tau_s > 0 && d.m > 0; };
  // The octave subset: from the smallest tau, each next point at least twice the last one's tau.
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < oadev.size(); ++i) {
    if (!usable(oadev[i])) continue;
    if (!idx.empty() && oadev[i].tau_s < 2 * oadev[idx.back()].tau_s * (1 - 1e-9)) continue;
    idx.push_back(i);
  }
  // The longest tau too when it is at least 1.5x the last octave point (log:N ends at the stop
  // ratio, (N-1)/4, up to an octave past the last power of two: the points that see K and R
  // most); its correlation with the octave point before it is taken as one octave's.
  for (std::size_t i = oadev.size(); i-- > 0;)
    if (usable(oadev[i])) {
      if (!idx.empty() && oadev[i].tau_s >= 1.5 * oadev[idx.back()].tau_s) idx.push_back(i);
      break;
    }
  return idx;
}

std::size_t phase_points(double record_s, double tau0) {
  return static_cast<std::size_t>(std::llround(record_s / tau0)) + 1;
}

LogScatter model_log_scatter(std::span<const double> tau_s, std::span<const std::size_t> m,
                             const std::array<double, 5>& theta_in, std::size_t n_phase) {
  std::array<double, 5> theta = theta_in;
  const double largest = *std::max_element(theta.begin(), theta.end());
  if (largest > 0 && std::isfinite(largest)) {
    int exponent = 0;
    std::frexp(largest, &exponent);
    for (double& t : theta) t = std::ldexp(t, -exponent);
  }
  Pts p({tau_s.begin(), tau_s.end()}, std::vector<double>(tau_s.size(), 1), {m.begin(), m.end()}, n_phase);
  set_model_edf(p, theta, n_phase);
  LogScatter out;
  for (const double nu : p.nu) out.bias.push_back(log_bias(nu));
  const Eigen::MatrixXd S = model_cov(p, theta, n_phase, 0);
  out.cov.assign(S.data(), S.data() + S.size());  // symmetric: row- and column-major alike
  return out;
}

namespace {
// Whether the model `theta` puts at one of the points before `from` at least kDroppedContradiction
// times the variance the point measured.
bool exceeds_dropped(const Pts& all, std::size_t from, const std::array<double, 5>& theta) {
  for (std::size_t i = 0; i < from; ++i) {
    if (model_sigma2(theta, all.tau[i]) >= kDroppedContradiction * all.s[i]) return true;
  }
  return false;
}
}  // namespace

namespace {

NoiseModelFit fit_in_units(std::span<const DevPoint> oadev, double record_s, double confidence, unsigned threads) {
  NoiseModelFit out;
  std::vector<double> tau, s;
  std::vector<std::size_t> m;
  for (const std::size_t i : octave_points(oadev)) {
    tau.push_back(oadev[i].tau_s);
    s.push_back(oadev[i].dev * oadev[i].dev);
    m.push_back(oadev[i].m);
  }
  const std::size_t n_all = tau.size();
  if (n_all < 3) {  // AICc needs n - k - 1 > 0 for one term
    out.reason = "fewer than 3 octave Allan points";
    return out;
  }
  const double tau0 = tau.front() / static_cast<double>(m.front());
  const std::size_t n_phase = phase_points(record_s, tau0);
  const Pts all(std::move(tau), std::move(s), std::move(m), n_phase);

  // The tau range where the IEEE 952 model is adequate (docs/analysis.md "Goodness of fit"): the
  // model is selected on the octave points from the shortest tau on; when its chi-square on the
  // covariance it implies is improbable (p < kGofAlpha), the shortest point is dropped and the
  // model selected again. What the five power laws miss on a real DUT is high-frequency (tones
  // folded by the sampling, the output filter, bursts): it sits at the shortest taus, where the
  // EDF is 1e5..1e6 and a 10 % ripple is hundreds of sigma, and it would otherwise decide the
  // model (and, carried as a model error, drown the long-tau points that decide K and R). When
  // no range of at least kMinGofPoints points is adequate, the last range tried is fitted with
  // the Birge model error instead, and the fit says so.
  // The subset fits of each selection round run over the cores there are (by now the deviations
  // are done); each fit is the same on any thread.
  Team team(std::max(1u, std::min(threads, std::thread::hardware_concurrency())));
  Selection sel;
  std::size_t from = 0;
  const std::size_t last_from = n_all > kMinGofPoints ? n_all - kMinGofPoints : 0;
  for (;; ++from) {
    sel = select_model(all.tail(from), n_phase, false, team);
    if ((sel.ok && sel.p_value >= kGofAlpha) || from >= last_from) break;
  }
  // What the five power laws miss at the short end (tones, the loop's and a filter's roll-off)
  // moves those points off the model, below it where a filter cuts the high frequencies: on the
  // paper's DUT the model from 0.5 s on puts 5-7x the variance measured at 1 ms, behind a 3 Hz
  // low-pass on a 100 Hz record N alone puts 60x at 0.01 s (a code review). What the data do not
  // allow is a term the model selection left out (AICc) that the widest model brings in at
  // kDroppedContradiction times the variance a dropped point measured: the AICc model agrees with
  // the dropped points and the widest does not, so the misfit was not at the short end but a chance
  // realisation at long tau. Every point is then kept and the misfit carried as the model error. A
  // metrologist's review found a white + random walk FM record with ten short points dropped and
  // Q at 263x the variance the 0.01 s point measured (16x its deviation; N 0.78x, its bounds
  // excluding the truth).
  // The widest model past the dropped points, kept for the terms below while the selection it was
  // fitted for stands (it is the same fit: the same points, model error and start).
  std::optional<std::pair<SubsetFit, Eigen::MatrixXd>> widest_kept;
  // Nor is it at the short end when leaving out fewer of the longest points (at most
  // kLongSagPoints, each of a few degrees of freedom) makes every short point fit: the misfit is
  // then a chance realisation at long tau, a random walk that came out flat over the last octaves,
  // whose deviations at small EDF fall further below the model than the log-normal approximation
  // of the chi-square test allows (at EDF 2, 0.04x the model has a probability of 4 %, the
  // approximation 0.07 %). A metrologist's review found a white FM + random walk FM record with the
  // last two octaves at 0.09x and 0.04x their truth, thirteen short points dropped, and a Q
  // (truth 0) at 4360x the variance the 1 ms point measured, N null. Every point is then kept,
  // without a model error (below).
  std::size_t long_cut = 0;  // the longest points whose leaving-out fits (0: none did)
  if (from > 1 && sel.ok) {
    const std::size_t most = std::min({kLongSagPoints, from - 1, n_all - kMinGofPoints});
    for (std::size_t cut = 1; cut <= most && long_cut == 0; ++cut) {
      const Selection head = select_model(all.head(n_all - cut), n_phase, false, team);
      if (head.ok && head.p_value >= kGofAlpha) long_cut = cut;
    }
  }
  const bool long_sag = long_cut > 0;
  out.long_tau_misfit = long_cut;
  if (long_sag) {
    from = 0;
    sel = select_model(all, n_phase, false, team);
  } else if (from > 0 && sel.ok) {
    Pts kept = all.tail(from);
    Eigen::MatrixXd W_wide;
    SubsetFit wide = widest_model(kept, n_phase, sel.delta, sel.best.theta, W_wide, team);
    if (wide.ok && exceeds_dropped(all, from, wide.theta) && !exceeds_dropped(all, from, sel.best.theta)) {
      from = 0;
      sel = select_model(all, n_phase, false, team);
    } else {
      widest_kept.emplace(std::move(wide), std::move(W_wide));
    }
  }
  out.gof_p = sel.ok ? sel.p_value : 0;
  out.dropped_short = from;
  // Not for a long-tau chance realisation: the model error is a share of the white terms (what
  // a DUT's tones add at short tau), so it cannot absorb a misfit at long tau and would widen the
  // short points instead (N's interval reached 0 on such a record): those points' own few degrees
  // of freedom already carry their scatter.
  if (sel.ok && sel.p_value < kGofAlpha && !long_sag) {
    sel = select_model(all.tail(from), n_phase, true, team);
    out.model_error = sel.delta;
    widest_kept.reset();
  }
  if (!sel.ok) {
    out.reason = sel.reason;
    return out;
  }
  Pts p = all.tail(from);
  const std::size_t n = p.tau.size();
  // Which terms are reported, and the covariance the values are fitted on, are the method's
  // (one sigma, as its coverage was measured: docs/analysis.md); only the bounds and the upper
  // limits take the confidence asked for, so the values and the nulls do not depend on it.
  const double z_method = boost::math::quantile(boost::math::normal(), (1 + kOneSigma) / 2);
  const double z = boost::math::quantile(boost::math::normal(), (1 + confidence) / 2);
  // The terms: the widest non-negative model on the tau range (not the AICc model, whose left-out
  // terms land in their neighbours: R on 6 h read 1.6x with K left out, covered 15 %).
  Eigen::MatrixXd W;
  SubsetFit best;
  if (widest_kept) {
    best = std::move(widest_kept->first);
    W = std::move(widest_kept->second);
  } else {
    best = widest_model(p, n_phase, sel.delta, sel.best.theta, W, team);
  }
  if (!best.ok) {
    best = sel.best;
    W = sel.W;
  }
  // The covariance of the bounds: the model plus every term left out at its upper limit. A term
  // the data cannot exclude still scatters the points (above all the ramp's cross term, which
  // without K would make the R-dominated points look nearly exact).
  set_model_edf(p, best.theta, n_phase);
  std::array<double, 5> th_cov = best.theta;
  bool widened = false;
  for (int k = 0; k < 5; ++k) {
    if (best.mask & (1 << k)) continue;
    const SubsetFit g = gls_subset(p, W, best.mask | (1 << k), best.theta, false);
    if (!g.ok) continue;
    th_cov[static_cast<std::size_t>(k)] = std::max(0.0, g.theta[static_cast<std::size_t>(k)]) + z_method * sd_of(g, k);
    widened = widened || th_cov[static_cast<std::size_t>(k)] > 0;
  }
  if (widened) {
    set_model_edf(p, th_cov, n_phase);
    W = model_cov(p, th_cov, n_phase, sel.delta).inverse();
    const SubsetFit f = gls_subset(p, W, best.mask, best.theta, true);
    if (f.ok) best = f;
  }
  // Reported (in_model): a term of this model with theta > 0 that either AICc selects (the data
  // support it over the model without it) or whose one-sigma interval excludes zero
  // (theta >= sd). Collinear terms (K and R over tau <= T/4 of a short record) can each be
  // insignificant in the widest model while together they are not: AICc reports the one that
  // carries the rise. The others are null with the interval's upper end as their upper limit.
  int report = 0;
  for (int k = 0; k < 5; ++k) {
    const double th = best.theta[static_cast<std::size_t>(k)];
    if ((best.mask & (1 << k)) && th > 0 && ((sel.best.mask & (1 << k)) || th >= z_method * sd_of(best, k))) report |= 1 << k;
  }
  // The reported terms' values: the model of those terms alone, refitted on the same covariance.
  // The widest model keeps every term the data cannot exclude, and one it cannot tell from 0
  // still takes a share: Q, free at the short end of records without it, took 0.1-0.5 % of N, so
  // N read low by 0.3-0.7 of its scatter, and its bounds, widened by that Q, held the truth in
  // 77-81 % for a stated 68.3 % (240 seeds per set, docs/analysis.md "Coverage over injected
  // noise"). Which terms are reported, the covariance of the bounds and the nulls' upper limits
  // stay the widest model's.
  SubsetFit shown = best;
  if (report != 0 && report != best.mask) {
    const SubsetFit g = gls_subset(p, W, report, best.theta, true);
    bool positive = g.ok;
    for (int k = 0; k < 5; ++k)
      if ((report & (1 << k)) && !(g.theta[static_cast<std::size_t>(k)] > 0)) positive = false;
    if (positive) shown = g;
  }
  const std::vector<SubsetFit> plausible = plausible_models(p, sel, n_phase, team);
  out.aicc = sel.aicc;
  out.chi2_per_dof = sel.chi2 / sel.dof;
  out.tau_s = p.tau;
  out.avar = p.s;
  out.edf = p.nu;
  for (int k = 0; k < 5; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    if (!(report & (1 << k)) && (best.mask & (1 << k))) {
      for (const auto& [u, zz] : {std::pair{&out.upper, z}, {&out.upper_method, z_method}})
        (*u)[kk] = std::sqrt(std::max(0.0, best.theta[kk]) + zz * sd_of(best, k));
    } else if (best.mask & (1 << k)) {
      const double th = shown.theta[kk], sd = sd_of(shown, k);
      out.in_model[kk] = true;
      out.z[kk] = sd > 0 ? th / sd : 0;
      out.value[kk] = std::sqrt(th);
      out.lo[kk] = std::sqrt(std::max(0.0, th - z * sd));
      out.hi[kk] = out.upper[kk] = std::sqrt(th + z * sd);
      // The data do not choose between the widest model and the AICc model (their chi-squares
      // differ by less than the terms' penalty): the bounds hold over both. A term the AICc
      // model does without has 0 as its lower bound; one it has, the wider of the two intervals.
      if (!(sel.best.mask & (1 << k))) {
        out.lo[kk] = 0;
      } else {
        const double tha = sel.best.theta[kk], sda = sd_of(sel.best, k);
        out.lo[kk] = std::min(out.lo[kk], std::sqrt(std::max(0.0, tha - z * sda)));
        out.hi[kk] = out.upper[kk] = std::max(out.hi[kk], std::sqrt(tha + z * sda));
      }
      // Likewise over every plausible model (above): one without the term (or with it at 0)
      // lowers the bound to 0; one with it, the union of the intervals.
      for (const SubsetFit& f : plausible) {
        const double thf = (f.mask & (1 << k)) ? f.theta[kk] : 0.0;
        if (!(thf > 0)) {
          out.lo[kk] = 0;
          continue;
        }
        const double sdf = sd_of(f, k);
        out.lo[kk] = std::min(out.lo[kk], std::sqrt(std::max(0.0, thf - z * sdf)));
        out.hi[kk] = out.upper[kk] = std::max(out.hi[kk], std::sqrt(thf + z * sdf));
      }
      for (std::size_t i = 0; i < n; ++i) {
        out.share[kk] = std::max(out.share[kk], th * noise_basis(k, p.tau[i]) / model_sigma2(shown.theta, p.tau[i]));
      }
    } else {
      // Upper limit: the model plus this term, its sign free (GLS from the model, theta_k = 0);
      // theta_k^+ + z sd(theta_k).
      SubsetFit f;
      if (W.size() > 0) f = gls_subset(p, W, best.mask | (1 << k), best.theta, false);
      for (const auto& [up, zz] : {std::pair{&out.upper, z}, {&out.upper_method, z_method}}) {
        if (f.ok) {
          (*up)[kk] = std::sqrt(std::max(0.0, f.theta[kk]) + zz * sd_of(f, k));
        } else {
          // No solution with the term: it cannot exceed what any one point allows alone.
          double u = std::numeric_limits<double>::infinity();
          for (std::size_t i = 0; i < n; ++i)
            u = std::min(u, p.s[i] * (1 + zz * std::sqrt(2 / p.nu[i])) / noise_basis(k, p.tau[i]));
          (*up)[kk] = std::sqrt(u);
        }
      }
    }
  }
  // Each null's linearised limit raised to the test's (inverted_upper), the terms over the team;
  // at the method's own confidence the two limits are one computation.
  struct Limit {
    std::size_t k;
    double* at;
    double z;
  };
  std::vector<Limit> limits;
  for (std::size_t k = 0; k < 5; ++k)
    if (!out.in_model[k]) {
      limits.push_back({k, &out.upper[k], z});
      if (z_method != z) limits.push_back({k, &out.upper_method[k], z_method});
    }
  team.run(limits.size(), [&](std::size_t i) {
    const Limit& l = limits[i];
    const double wald = *l.at * *l.at;
    *l.at = std::sqrt(inverted_upper(p, th_cov, best, static_cast<int>(l.k), l.z, n_phase, sel.delta, wald));
  });
  for (std::size_t k = 0; k < 5; ++k)
    if (!out.in_model[k] && z_method == z) out.upper_method[k] = out.upper[k];
  for (int k = 0; k < 5; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    if (!out.in_model[kk])  // a null's upper limit holds over the plausible models too
      for (const SubsetFit& f : plausible)
        if ((f.mask & (1 << k)) && f.theta[kk] > 0)
          for (const auto& [up, zz] : {std::pair{&out.upper, z}, {&out.upper_method, z_method}})
            (*up)[kk] = std::max((*up)[kk], std::sqrt(f.theta[kk] + zz * sd_of(f, k)));
    // Nor may a null's upper limit contradict a dropped short point (kDroppedContradiction): fitted
    // from 10-20 s on, Q's limit reached 60x what the 0.01 s point allows alone (a metrologist's
    // review, white + random walk FM records).
    if (!out.in_model[kk])
      for (std::size_t j = 0; j < from; ++j) {
        const double cap = std::sqrt(kDroppedContradiction * all.s[j] / noise_basis(k, all.tau[j]));
        out.upper[kk] = std::min(out.upper[kk], cap);
        out.upper_method[kk] = std::min(out.upper_method[kk], cap);
      }
  }
  out.ok = true;
  return out;
}

}  // namespace

// The fit works in units where the median deviation is in [0.5, 1): the points are scaled by a
// power of two, which is exact, and the terms scaled back. In the record's own units theta is a
// variance and its covariance a variance squared, which under- or overflowed a double beyond
// about 1e+-70 (a review: 1e-80 and 1e90 g got 'no non-negative model fits'), and the likelihood's
// ln mu moved with the unit, so on a short record which terms were reported changed when the
// values were multiplied by 2^10 (a second review). Now a unit that is a power of two gives the
// same fit bit for bit, and any other unit the same to rounding.
NoiseModelFit fit_noise_model(std::span<const DevPoint> oadev, double record_s, double confidence, unsigned threads) {
  std::vector<double> devs;
  for (const DevPoint& p : oadev)
    if (std::isfinite(p.dev) && p.dev > 0) devs.push_back(p.dev);
  const int e = median_exponent(std::move(devs));
  if (e == 0) return fit_in_units(oadev, record_s, confidence, threads);
  std::vector<DevPoint> scaled(oadev.begin(), oadev.end());
  for (DevPoint& p : scaled) {
    p.dev = std::ldexp(p.dev, -e);
    p.lo = std::ldexp(p.lo, -e);
    p.hi = std::ldexp(p.hi, -e);
  }
  NoiseModelFit f = fit_in_units(scaled, record_s, confidence, threads);
  for (std::array<double, 5>* a : {&f.value, &f.lo, &f.hi, &f.upper, &f.upper_method})
    for (double& x : *a) x = std::ldexp(x, e);
  for (double& v : f.avar) v = std::ldexp(v, 2 * e);
  return f;
}

}  // namespace rig::analysis
