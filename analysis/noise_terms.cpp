#include "analysis/noise_terms.hpp"

#include "analysis/edf.hpp"

#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

namespace rig::analysis {

namespace {

const char* const kNames[5] = {"Q", "N", "B", "K", "R"};
const double kSlopes[5] = {-1, -0.5, 0, 0.5, 1};
const char* const kUnits[5] = {"g*s", "g*s^0.5", "g", "g/s^0.5", "g/s"};

// Term value from sigma at tau on its own slope: the relations sigma_q .. sigma_r of
// noise_terms.hpp (IEEE 952 Annex C) solved for the coefficient.
double term_from_sigma(int k, double sigma, double tau) {
  switch (k) {
    case 0: return sigma * tau / std::sqrt(3.0);
    case 1: return sigma * std::sqrt(tau);
    case 2: return sigma / kBiasFactor;
    case 3: return sigma * std::sqrt(3 / tau);
    default: return sigma * std::sqrt(2.0) / tau;
  }
}

std::string fmt(double v) {
  std::ostringstream o;
  o.precision(3);
  o << v;
  return o.str();
}

// A term the data do not support: null, `hi` its upper limit, the reason in both forms
// (Term::reason_without_limit: the passport states the limit again in its own unit).
void null_with_limit(Term& t, std::size_t k, const std::string& why, double upper) {
  t.hi = upper;
  t.reason_without_limit = why;
  t.reason = why + "; upper limit " + kNames[k] + " <= " + fmt(upper) + " " + kUnits[k];
}

// A note after a term's reason, in both its forms (Term::reason_without_limit).
void add_note(Term& t, const std::string& note) {
  t.reason += note;
  if (!t.reason_without_limit.empty()) t.reason_without_limit += note;
}

double poly(const std::array<double, 5>& c, double x) {
  double y = 0;
  for (int k = 4; k >= 0; --k) y = y * x + c[static_cast<std::size_t>(k)];
  return y;
}
double dpoly(const std::array<double, 5>& c, double x) {
  return c[1] + 2 * c[2] * x + 3 * c[3] * x * x + 4 * c[4] * x * x * x;
}

// The paper polynomial's design matrix of `degree` at the log10 taus xs: row i is 1, x_i, .., x_i^d.
Eigen::MatrixXd poly_design(std::span<const double> xs, int degree) {
  Eigen::MatrixXd A(static_cast<Eigen::Index>(xs.size()), degree + 1);
  for (std::size_t i = 0; i < xs.size(); ++i) {
    double p = 1;
    for (int k = 0; k <= degree; ++k, p *= xs[i]) A(static_cast<Eigen::Index>(i), k) = p;
  }
  return A;
}

PaperFit paper_fit(std::span<const DevPoint> pts) {
  PaperFit f;
  std::vector<double> xs, ys;
  for (const auto& p : pts)
    if (p.dev > 0 && p.tau_s > 0) xs.push_back(std::log10(p.tau_s)), ys.push_back(std::log10(p.dev));
  if (xs.size() < 3) {
    f.reason = "fewer than 3 Allan points";
    return f;
  }
  f.degree = static_cast<int>(std::min<std::size_t>(4, xs.size() - 1));
  const Eigen::MatrixXd A = poly_design(xs, f.degree);
  const Eigen::VectorXd b = Eigen::Map<const Eigen::VectorXd>(ys.data(), static_cast<Eigen::Index>(ys.size()));
  const Eigen::VectorXd c = A.colPivHouseholderQr().solve(b);
  for (int k = 0; k <= f.degree; ++k) f.coef[static_cast<std::size_t>(k)] = c(k);

  // Inflection points: roots of y'' = 2c2 + 6c3 x + 12c4 x^2 inside the measured range.
  const double x_lo = xs.front(), x_hi = xs.back();
  std::vector<double> infl;
  const double qa = 12 * f.coef[4], qb = 6 * f.coef[3], qc = 2 * f.coef[2];
  if (std::abs(qa) > 1e-12) {
    const double disc = qb * qb - 4 * qa * qc;
    if (disc >= 0) {
      const double r = std::sqrt(disc);
      infl = {(-qb - r) / (2 * qa), (-qb + r) / (2 * qa)};
    }
  } else if (std::abs(qb) > 1e-12) {
    infl = {-qc / qb};
  }
  std::sort(infl.begin(), infl.end());
  std::vector<double> cuts{x_lo};
  for (double x : infl)
    if (x > x_lo && x < x_hi) {
      cuts.push_back(x);
      f.inflection_tau_s.push_back(std::pow(10.0, x));
    }
  cuts.push_back(x_hi);
  for (std::size_t s = 0; s + 1 < cuts.size(); ++s) {
    Segment seg;
    const double xm = (cuts[s] + cuts[s + 1]) / 2;
    seg.tau_lo_s = std::pow(10.0, cuts[s]);
    seg.tau_hi_s = std::pow(10.0, cuts[s + 1]);
    seg.tau_mid_s = std::pow(10.0, xm);
    seg.sigma_mid = std::pow(10.0, poly(f.coef, xm));
    seg.slope = dpoly(f.coef, xm);
    int best = 0;
    for (int k = 1; k < 5; ++k)
      if (std::abs(seg.slope - kSlopes[k]) < std::abs(seg.slope - kSlopes[best])) best = k;
    seg.term = kNames[best];
    seg.term_value = term_from_sigma(best, seg.sigma_mid, seg.tau_mid_s);
    f.segments.push_back(seg);
  }
  f.ok = true;
  return f;
}

// The one model (noise_model.hpp) as the rig's terms: a term in the model with its bounds, a
// term not in it null with its upper limit in `hi`.
WlsFit wls_from_model(const NoiseModelFit& m) {
  WlsFit w;
  w.ok = m.ok;
  w.reason = m.reason;
  w.points = m.tau_s.size();
  w.chi2_per_dof = m.chi2_per_dof;
  w.model_error = m.model_error;
  w.share = m.share;
  w.z = m.z;
  Term* terms[5] = {&w.Q, &w.N, &w.B, &w.K, &w.R};
  const std::string range =
      m.tau_s.empty() ? std::string() : " over tau = " + fmt(m.tau_s.front()) + ".." + fmt(m.tau_s.back()) + " s";
  for (std::size_t k = 0; k < 5; ++k) {
    Term& t = *terms[k];
    t.unit = kUnits[k];
    if (!m.ok) {
      t.reason = "model fit failed: " + m.reason;
    } else if (m.in_model[k]) {
      t.value = m.value[k];
      t.lo = m.lo[k];
      t.hi = m.hi[k];
      t.reason = std::string("model (GLS on the octave Allan points; the terms AICc or the widest non-negative model's interval supports, fitted together)") + range;
    } else {
      null_with_limit(t, k, "not supported by the data (AICc; interval includes 0)" + range, m.upper[k]);
    }
  }
  return w;
}

// The EDF of sigma(tau_cp), the paper method's reading: the model's EDF (model_edf: the noise the
// fitted terms imply, not the per-tau identification's) at the Allan point nearest tau_cp;
// without a model, that point's own EDF.
std::optional<double> paper_b_edf(std::span<const DevPoint> pts, const NoiseModelFit& m, double tau_cp, double record_s) {
  const DevPoint* near = nullptr;
  for (const DevPoint& p : pts)
    if (p.tau_s > 0 && p.m > 0 && (!near || std::abs(std::log(p.tau_s / tau_cp)) < std::abs(std::log(near->tau_s / tau_cp))))
      near = &p;
  if (!near) return std::nullopt;
  if (m.ok) {
    const double tau0 = near->tau_s / static_cast<double>(near->m);
    std::array<double, 5> theta{};
    for (std::size_t k = 0; k < 5; ++k) theta[k] = m.value[k] * m.value[k];
    const std::array<double, 5> mu = term_sigma2(theta, near->tau_s);
    return model_edf(mu, near->m, phase_points(record_s, tau0));
  }
  if (near->edf > 0) return near->edf;
  return std::nullopt;
}

// The EDF of sigma^2(tau_cp) as the paper's polynomial reads it. Its value at x* = log10 tau_cp is
// a weighted sum of every point's log10 sigma, with the least-squares hat row a = A (A^T A)^-1
// e(x*) (A the polynomial's design matrix, e(x*) = (1, x*, .., x*^d)), so ln sigma^2(tau_cp) =
// sum_i a_i ln s_i and its variance is a^T Sigma a over the covariance of ln s_i (Sigma). The
// model's covariance (model_log_scatter: its EDF and octave correlations) is for octave-spaced
// points, and the polynomial reads a denser grid; each point is taken as the octave point nearest
// it in log tau, fully correlated with it (points within half an octave are strongly correlated;
// sub-octave correlations are not in the model). Returned as the chi-square EDF with that variance
// of ln sigma^2 (2/nu to first order). Without a model, nullopt. A single Allan point's interval
// (its EDF at tau_cp) was narrower than the polynomial's scatter: 49/100 on flicker alone, where
// the polynomial carried the long taus' scatter into its middle (docs/analysis.md).
std::optional<double> paper_poly_edf(std::span<const DevPoint> pts, const PaperFit& f, double tau_cp,
                                     const NoiseModelFit& m, double record_s) {
  if (!m.ok || !f.ok || f.degree < 1 || !(tau_cp > 0)) return std::nullopt;
  const std::vector<std::size_t> oct = octave_points(pts);
  if (oct.empty()) return std::nullopt;
  std::vector<double> oct_tau;
  std::vector<std::size_t> oct_m;
  for (const std::size_t i : oct) {
    if (!(pts[i].tau_s > 0) || pts[i].m == 0) return std::nullopt;
    oct_tau.push_back(pts[i].tau_s), oct_m.push_back(pts[i].m);
  }
  std::vector<double> xs;
  std::vector<std::size_t> bin;  // each polynomial point's octave point
  for (const DevPoint& p : pts) {
    if (!(p.dev > 0 && p.tau_s > 0)) continue;  // the points paper_fit reads
    xs.push_back(std::log10(p.tau_s));
    std::size_t best = 0;
    for (std::size_t j = 1; j < oct_tau.size(); ++j)
      if (std::abs(std::log(p.tau_s / oct_tau[j])) < std::abs(std::log(p.tau_s / oct_tau[best]))) best = j;
    bin.push_back(best);
  }
  const auto n = static_cast<Eigen::Index>(xs.size()), d = static_cast<Eigen::Index>(f.degree);
  if (n <= d) return std::nullopt;
  const Eigen::MatrixXd A = poly_design(xs, f.degree);
  const double xstar = std::log10(tau_cp);
  const Eigen::VectorXd e = poly_design(std::span<const double>(&xstar, 1), f.degree).row(0).transpose();
  // a = A (A^T A)^-1 e by the QR of A (A = QR: a = Q R^-T e; no pivoting needed for the hat row).
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(A);
  const Eigen::MatrixXd R = qr.matrixQR().topRows(d + 1).triangularView<Eigen::Upper>();
  const Eigen::VectorXd u = R.transpose().triangularView<Eigen::Lower>().solve(e);
  Eigen::VectorXd qu = Eigen::VectorXd::Zero(n);
  qu.head(d + 1) = u;
  const Eigen::VectorXd a = qr.householderQ() * qu;
  Eigen::VectorXd w = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(oct_tau.size()));
  for (Eigen::Index i = 0; i < n; ++i) w(static_cast<Eigen::Index>(bin[static_cast<std::size_t>(i)])) += a(i);
  std::array<double, 5> theta{};
  for (std::size_t k = 0; k < 5; ++k) theta[k] = m.value[k] * m.value[k];
  const double tau0 = oct_tau.front() / static_cast<double>(oct_m.front());
  const std::size_t n_phase = phase_points(record_s, tau0);
  const LogScatter sc = model_log_scatter(oct_tau, oct_m, theta, n_phase);
  const auto k = static_cast<Eigen::Index>(oct_tau.size());
  const Eigen::Map<const Eigen::MatrixXd> S(sc.cov.data(), k, k);
  const double var = w.dot(S * w);
  if (!(var > 0) || !std::isfinite(var)) return std::nullopt;
  return 2 / var;
}

// The model's sigma^2 at tau: the sum of its reported terms' Allan variances (IEEE 952 Annex C).
double model_variance(const WlsFit& model, double tau) {
  double var = 0;
  const std::pair<const Term*, double (*)(double, double)> terms[] = {
      {&model.Q, sigma_q}, {&model.N, sigma_n}, {&model.B, sigma_b}, {&model.K, sigma_k}, {&model.R, sigma_r}};
  for (const auto& [t, sigma] : terms)
    if (t->value) var += std::pow(sigma(*t->value, tau), 2);
  return var;
}

// sigma^2(tau_cp) is the sum of every term's share (the model, noise_terms.hpp), so
// sigma(tau_cp)/0.664 reads B only where flicker is all of it and is above B wherever another
// term adds (an N-K crossing read as a floor: the paper's B is biased up). Its chi-square
// interval therefore bounds B from above only; from below B is bounded by what the model
// leaves to flicker, so the lower end is the lower of the two (0 when the model has no B).
// (Scaling the chi-square lower end by sqrt of the model's flicker share instead covered the
// truth less often: 72 % against 88 % in the coverage suite's K set, docs/analysis.md.)
void lower_to_the_models_flicker(Term& b, const WlsFit& model, double tau_cp) {
  if (!model.ok || !b.lo) return;
  const double model_lo = model.B.value ? model.B.lo.value_or(0.0) : 0.0;
  if (model_lo >= *b.lo) return;
  const double total = model_variance(model, tau_cp);
  const double flicker = model.B.value ? std::pow(sigma_b(*model.B.value, tau_cp), 2) : 0.0;
  b.lo = model_lo;
  std::ostringstream r;
  r << "; flicker is " << std::lround(total > 0 ? 100 * flicker / total : 0.0)
    << " % of the model's sigma^2 at tau_cp: sigma(tau_cp)/0.664 bounds B from above, the lower bound is the model's";
  b.reason += r.str();
}

// R from the record's drift (docs/analysis.md "R from the record's drift"). A rate ramp is a
// deterministic slope of the output; the least-squares slope of the record estimates it without
// bias, and the noise scatters it by sd (drift.hpp: each term's share at the model's value, a term
// the model leaves out at its upper limit, which the data cannot exclude). On the Allan curve R
// and K are nearly collinear up to T/4 (the random walk's realisation rises like a ramp), and
// bounds from the curve held the truth on 50 % of 6-h records at 68.3 %; the slope's scatter is
// that realisation's, in closed form (coverage measured in docs/analysis.md).
// sd^2 is estimated: its EDF is Welch-Satterthwaite's over the model terms' EDFs (a term in the
// model with theta / sd(theta) = z has EDF 2 z^2; one at its upper limit counts as known), and
// the bounds take Student's t at that EDF. Reported when the drift is supported as AIC admits a
// term to the model: fitting it lowers the chi-square by more than 2, the price of one parameter,
// i.e. |slope| >= sqrt(2) t sd (at |slope| >= t sd, a third of records with a random walk and no
// ramp reported one); else null with |slope| + t sd as the upper limit.
constexpr double kDriftSupport = std::numbers::sqrt2;
void read_r_from_drift(NoiseTerms& out, const Drift& d, double confidence) {
  const NoiseModelFit& m = out.model;
  if (!m.ok || !d.ok()) return;
  std::array<double, 4> q{};
  for (std::size_t k = 0; k < 4; ++k) q[k] = m.in_model[k] ? m.value[k] : m.upper_method[k];
  const std::array<double, 4> v = drift_variance_terms(q, d);
  double var = 0, denom = 0;
  for (std::size_t k = 0; k < 4; ++k) var += v[k];
  if (!(var > 0)) return;
  // Welch-Satterthwaite on the shares v_k / var: var^2 itself underflows for records in units far
  // from g (a review: 1e-80 g read the normal quantile, 1e90 g Student's t at EDF 1).
  for (std::size_t k = 0; k < 4; ++k)
    if (m.in_model[k] && m.z[k] > 0) denom += (v[k] / var) * (v[k] / var) / (2 * m.z[k] * m.z[k]);
  DriftReading r;
  r.slope = d.slope;
  r.sd = std::sqrt(var);
  // (at least 1: Student's t has no quantile below; reached only by a term with z < 0.71)
  r.edf = denom > 0 ? std::max(1.0, 1 / denom) : std::numeric_limits<double>::infinity();
  const bool estimated = std::isfinite(r.edf) && r.edf < 1e6;  // beyond, t is the normal to 1e-6
  const auto quantile = [&](double c) {
    const double p = (1 + c) / 2;
    return estimated ? boost::math::quantile(boost::math::students_t(r.edf), p)
                     : boost::math::quantile(boost::math::normal(), p);
  };
  // Support is the method's rule at one sigma (below); the bounds are at the confidence asked for.
  r.quantile = quantile(confidence);
  out.drift = r;
  const double b = std::abs(d.slope), half = r.quantile * r.sd;
  const double support = kDriftSupport * quantile(kOneSigma) * r.sd;
  Term t;
  t.unit = kUnits[4];
  // No number in the term's unit here: the passport restates the reason per hour (the slope and
  // its scatter in g/s are analysis.json's noise_terms.drift).
  std::ostringstream how;
  how << "least-squares drift of the record (" << (d.slope < 0 ? "falling" : "rising")
      << "; its scatter from the model's N, B, K";
  std::string limits;  // the terms taken at their upper limits: the scatter is then an upper bound too
  int at_limit = 0;
  for (std::size_t k = 1; k < 4; ++k)
    if (!m.in_model[k] && v[k] > 0.01 * var) limits += std::string(at_limit++ ? ", " : "") + kNames[k];
  if (at_limit) how << " (" << limits << " at " << (at_limit > 1 ? "their" : "its") << " upper limit)";
  how << ", ";
  if (estimated) how << "Student's t at EDF " << fmt(r.edf) << ")";
  else how << "normal quantile)";
  if (b >= support) {
    t.value = b;
    t.lo = std::max(0.0, b - half);
    t.hi = b + half;
    t.reason = how.str();
  } else {
    null_with_limit(t, 4, "not supported by the data: " + how.str() + " within its scatter", b + half);
  }
  out.R = t;
}

}  // namespace

NoiseTerms no_noise_terms(const std::string& why, double confidence) {
  NoiseTerms out;
  out.confidence = confidence;
  out.paper.reason = out.model.reason = out.wls.reason = why;
  Term* const terms[5] = {&out.Q, &out.N, &out.B, &out.K, &out.R};
  Term* const fitted[5] = {&out.wls.Q, &out.wls.N, &out.wls.B, &out.wls.K, &out.wls.R};
  for (std::size_t k = 0; k < 5; ++k) {
    terms[k]->unit = fitted[k]->unit = kUnits[k];
    terms[k]->reason = fitted[k]->reason = why;
  }
  return out;
}

NoiseTerms noise_terms(std::span<const DevPoint> oadev, double record_length_s, double r_min_record_s,
                       const std::optional<Drift>& drift, double confidence) {
  // Every point 0: the fits would fail on the points ("fewer than 3 Allan points" with 8 there, a
  // review), where the record has no noise at all.
  if (!oadev.empty() && std::all_of(oadev.begin(), oadev.end(), [](const DevPoint& p) { return p.dev == 0; }))
    return no_noise_terms("every Allan deviation is 0 (a constant record): no noise to fit", confidence);
  NoiseTerms out;
  out.confidence = confidence;
  out.paper = paper_fit(oadev);
  // One model, every term the data supports (noise_model.hpp): no record-length rule in the fit.
  out.model = fit_noise_model(oadev, record_length_s, confidence);
  out.wls = wls_from_model(out.model);
  // Said as what it means for the value, not as a missing requirement ("requires" read as a
  // mandatory value missing on a passport that passed: a technician's review).
  const std::string too_short = "; the record is shorter than the " + fmt(r_min_record_s / 3600) +
                                " h the profile asks for R (r_min_record_s): over it a random walk's trend reads as a ramp "
                                "too, so this is not yet the DUT's R";
  if (out.wls.R.value && record_length_s < r_min_record_s) out.wls.R.reason += too_short;
  out.Q = out.wls.Q;
  out.N = out.wls.N;
  out.K = out.wls.K;
  out.R = out.wls.R;
  if (drift) {
    read_r_from_drift(out, *drift, confidence);
    if (out.drift && out.R.value && record_length_s < r_min_record_s) out.R.reason += too_short;
  }
  if (!out.wls.ok) {
    for (Term* t : {&out.Q, &out.N, &out.K, &out.R}) t->reason = "fit failed: " + out.wls.reason;
  }
  out.Q.unit = kUnits[0];
  out.N.unit = kUnits[1];
  out.K.unit = kUnits[3];
  out.R.unit = kUnits[4];
  out.B.unit = kUnits[2];
  if (!out.R.value) {
    // R (rate ramp) needs tau well beyond where K dominates; the paper puts it at > 50 h.
    if (record_length_s < 2 * 50 * 3600.0 && out.R.reason.find("longer record") == std::string::npos)
      add_note(out.R, "; needs a longer record");
  }
  // B by the paper's method: the flat segment (slope nearest 0, |slope| < 0.25). Flat over the
  // whole segment, not only at its middle: a convex segment from white FM's -1/2 to random walk's
  // +1/2 has a middle slope near 0, and was labelled flat over three decades where sigma fell and
  // rose fivefold (a metrologist's review); its bottom is the polynomial's minimum, read below.
  // Between inflection points the second derivative keeps its sign, so the slope is monotonic
  // along a segment: flat throughout when flat at both ends.
  const auto flat_throughout = [&](const Segment& s) {
    return std::abs(dpoly(out.paper.coef, std::log10(s.tau_lo_s))) < 0.25 &&
           std::abs(dpoly(out.paper.coef, std::log10(s.tau_hi_s))) < 0.25;
  };
  const Segment* flat = nullptr;
  if (out.paper.ok)
    for (const auto& s : out.paper.segments)
      if (std::abs(s.slope) < 0.25 && flat_throughout(s) && (!flat || std::abs(s.slope) < std::abs(flat->slope)))
        flat = &s;
  if (flat) {
    out.tau_cp_s = flat->tau_mid_s;
    out.sigma_cp = flat->sigma_mid;
    out.b_method = "flat_segment";
    out.flat_tau_from_s = flat->tau_lo_s;
    out.flat_tau_to_s = flat->tau_hi_s;
    out.B.reason = "paper: sigma(tau_cp) / 0.664, tau_cp the middle of the flat segment tau = " + fmt(flat->tau_lo_s) +
                   ".." + fmt(flat->tau_hi_s) + " s";
  } else if (out.paper.ok) {
    // No segment between inflection points is flat (a smooth -1/2 -> 0 -> +1/2 curve is convex and
    // has none): read the flat bottom where the polynomial's slope crosses zero, as IEEE 952 does.
    const double x_lo = std::log10(oadev.front().tau_s), x_hi = std::log10(oadev.back().tau_s);
    double best_x = 0, best_y = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= 2000; ++i) {
      const double x = x_lo + (x_hi - x_lo) * i / 2000.0;
      const double y = poly(out.paper.coef, x);
      if (y < best_y) best_y = y, best_x = x;
    }
    // The grid finds the minimum's cell; its slope's zero in the cells either side, by bisection,
    // is the minimum itself (the grid point was up to 0.3 % off in tau_cp, a review).
    const double step = (x_hi - x_lo) / 2000.0;
    double a = std::max(x_lo, best_x - step), b = std::min(x_hi, best_x + step);
    if (dpoly(out.paper.coef, a) < 0 && dpoly(out.paper.coef, b) > 0) {
      for (int i = 0; i < 200 && b - a > 0; ++i) {
        const double mid = 0.5 * (a + b);
        if (mid <= a || mid >= b) break;  // a and b adjacent doubles
        (dpoly(out.paper.coef, mid) < 0 ? a : b) = mid;
      }
      const double x = 0.5 * (a + b), y = poly(out.paper.coef, x);
      if (y <= best_y) best_y = y, best_x = x;
    }
    const bool interior = best_x > x_lo + 0.02 * (x_hi - x_lo) && best_x < x_hi - 0.02 * (x_hi - x_lo);
    if (interior && std::abs(dpoly(out.paper.coef, best_x)) < 0.05) {
      out.tau_cp_s = std::pow(10.0, best_x);
      out.sigma_cp = std::pow(10.0, best_y);
      out.b_method = "polynomial_minimum";
      out.B.reason = "paper polynomial: no flat segment between inflections; tau_cp at its minimum";
    }
  }
  if (out.sigma_cp) {
    out.B.value = *out.sigma_cp / kBiasFactor;
    out.b_edf = paper_poly_edf(oadev, out.paper, *out.tau_cp_s, out.model, record_length_s);
    if (!out.b_edf) out.b_edf = paper_b_edf(oadev, out.model, *out.tau_cp_s, record_length_s);
    if (out.b_edf) {  // the chi-square bounds of sigma(tau_cp) at that EDF, over 0.664
      const auto [lo, hi] = chi2_bounds(*out.B.value, *out.b_edf, confidence);
      out.B.lo = lo;
      out.B.hi = hi;
      lower_to_the_models_flicker(out.B, out.wls, *out.tau_cp_s);
    }
  } else {
    out.B = out.wls.B;
    out.B.unit = kUnits[2];
    out.B.reason_without_limit.clear();  // every reason below replaces the model's, limit clause and all
    if (out.B.value) out.b_method = "least_squares";
    if (out.B.value) out.B.reason = "least squares (the model's B: the Allan curve has no flat part to read)";
    else if (!out.paper.ok) out.B.reason = "paper fit failed: " + out.paper.reason;
    else {
      std::ostringstream r;  // (a stream: GCC 12 -O3 warns falsely on long string concatenations)
      r << "no flat segment (|slope| < 0.25) and no interior minimum in tau = " << oadev.front().tau_s << ".."
        << oadev.back().tau_s << " s";
      out.B.reason = r.str();
    }
  }
  std::vector<double> taus;
  for (const auto& p : oadev)
    if (p.tau_s > 0) taus.push_back(p.tau_s);
  out.curves = fitted_curves(out, taus);
  return out;
}

FittedCurves fitted_curves(const NoiseTerms& t, std::span<const double> taus) {
  FittedCurves c;
  c.tau_s.assign(taus.begin(), taus.end());
  auto curve = [&](const Term& term, double (*sigma)(double, double)) {
    std::vector<double> v;
    if (term.value)
      for (double tau : taus) v.push_back(sigma(*term.value, tau));
    return v;
  };
  c.Q = curve(t.Q, sigma_q);
  c.N = curve(t.N, sigma_n);
  c.B = curve(t.B, sigma_b);
  c.K = curve(t.K, sigma_k);
  c.R = curve(t.R, sigma_r);
  const WlsFit& m = t.wls;
  if (m.Q.value || m.N.value || m.B.value || m.K.value || m.R.value)
    for (double tau : taus) c.lsq_fit.push_back(std::sqrt(model_variance(m, tau)));
  if (t.paper.ok)
    for (double tau : taus) c.paper_poly.push_back(std::pow(10.0, poly(t.paper.coef, std::log10(tau))));
  return c;
}

}  // namespace rig::analysis
