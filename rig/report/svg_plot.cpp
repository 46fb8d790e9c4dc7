#include "rig/report/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <vector>

namespace rig::report {

using namespace rig::analysis;  // the figures plot the analysis library's results

namespace {

constexpr double kW = 820, kH = 560, kL = 90, kR = 30, kT = 50, kB = 70;

std::string esc(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<') o += "&lt;";
    else if (c == '>') o += "&gt;";
    else if (c == '&') o += "&amp;";
    else o += c;
  }
  return o;
}

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}

// A log-log (or log-x, linear-y) frame mapping data to pixels, with decade grid lines.
class Frame {
 public:
  Frame(double x0, double x1, double y0, double y1, bool logy = true)
      : lx0_(std::floor(std::log10(x0))), lx1_(std::ceil(std::log10(x1))), logy_(logy) {
    if (logy) {
      ly0_ = std::floor(std::log10(y0));
      ly1_ = std::ceil(std::log10(y1));
    } else {
      ly0_ = std::floor(y0 / 10) * 10;
      ly1_ = std::ceil(y1 / 10) * 10;
    }
    if (lx1_ <= lx0_) lx1_ = lx0_ + 1;
    if (ly1_ <= ly0_) ly1_ = ly0_ + (logy ? 1 : 10);
  }
  double px(double x) const { return kL + (std::log10(x) - lx0_) / (lx1_ - lx0_) * (kW - kL - kR); }
  double py(double y) const {
    const double v = logy_ ? std::log10(y) : y;
    return kT + (ly1_ - v) / (ly1_ - ly0_) * (kH - kT - kB);
  }
  bool inside_y(double y) const { return y > 0 || !logy_; }
  std::string grid(const std::string& xlabel, const std::string& ylabel, const std::string& title) const {
    std::ostringstream o;
    o << "<rect x='" << kL << "' y='" << kT << "' width='" << kW - kL - kR << "' height='" << kH - kT - kB
      << "' fill='white' stroke='#333'/>\n";
    for (double e = lx0_; e <= lx1_; ++e) {
      const double x = px(std::pow(10.0, e));
      o << "<line x1='" << x << "' y1='" << kT << "' x2='" << x << "' y2='" << kH - kB << "' stroke='#ddd'/>"
        << "<text x='" << x << "' y='" << kH - kB + 18 << "' text-anchor='middle' font-size='12'>1e" << e
        << "</text>\n";
    }
    const double step = logy_ ? 1 : std::max(10.0, std::round((ly1_ - ly0_) / 8 / 10) * 10);
    for (double e = ly0_; e <= ly1_ + 1e-9; e += step) {
      const double y = logy_ ? py(std::pow(10.0, e)) : py(e);
      o << "<line x1='" << kL << "' y1='" << y << "' x2='" << kW - kR << "' y2='" << y << "' stroke='#ddd'/>"
        << "<text x='" << kL - 6 << "' y='" << y + 4 << "' text-anchor='end' font-size='12'>"
        << (logy_ ? "1e" + num(e) : num(e)) << "</text>\n";
    }
    o << "<text x='" << (kL + kW - kR) / 2 << "' y='" << kH - 25 << "' text-anchor='middle' font-size='14'>"
      << esc(xlabel) << "</text>\n"
      << "<text x='20' y='" << (kT + kH - kB) / 2 << "' text-anchor='middle' font-size='14' transform='rotate(-90 20 "
      << (kT + kH - kB) / 2 << ")'>" << esc(ylabel) << "</text>\n"
      << "<text x='" << kW / 2 << "' y='30' text-anchor='middle' font-size='16'>" << esc(title) << "</text>\n";
    return o.str();
  }

 private:
  double lx0_, lx1_, ly0_ = 0, ly1_ = 1;
  bool logy_;
};

std::string head() {
  std::ostringstream o;
  o << "<svg xmlns='http://www.w3.org/2000/svg' width='" << kW << "' height='" << kH << "' viewBox='0 0 " << kW << ' '
    << kH << "' font-family='sans-serif'>\n";
  return o.str();
}

}  // namespace

std::string allan_svg(std::span<const DevPoint> pts, const NoiseTerms& t, const std::string& title,
                      const std::string& unit) {
  std::vector<DevPoint> v;
  for (const auto& p : pts)
    if (p.dev > 0 && p.tau_s > 0) v.push_back(p);
  std::ostringstream o;
  o << head();
  if (v.empty()) {
    o << "<text x='40' y='60'>no Allan points</text></svg>\n";
    return o.str();
  }
  double ylo = std::numeric_limits<double>::max(), yhi = 0;
  for (const auto& p : v) {
    ylo = std::min(ylo, p.lo > 0 ? p.lo : p.dev);
    yhi = std::max(yhi, p.hi > 0 ? p.hi : p.dev);
  }
  const double x0 = v.front().tau_s, x1 = v.back().tau_s;
  const Frame f(x0, x1, ylo, yhi);
  o << f.grid("tau, s", "Allan deviation, " + unit, title);
  o << "<clipPath id='plot'><rect x='" << kL << "' y='" << kT << "' width='" << kW - kL - kR << "' height='"
    << kH - kT - kB << "'/></clipPath>\n<g clip-path='url(#plot)'>\n";
  // Weighted-fit term lines (IEEE 952 slopes) and their sum.
  const struct {
    const Term* term;
    const char* name;
    const char* color;
    double (*sigma)(double v, double tau);
  } lines[] = {
      {&t.wls.Q, "Q", "#9467bd", [](double q, double tau) { return std::sqrt(3.0) * q / tau; }},
      {&t.wls.N, "N", "#1f77b4", [](double n, double tau) { return n / std::sqrt(tau); }},
      {&t.wls.B, "B", "#2ca02c", [](double b, double) { return kBiasFactor * b; }},
      {&t.wls.K, "K", "#d62728", [](double k, double tau) { return k * std::sqrt(tau / 3); }},
      {&t.wls.R, "R", "#8c564b", [](double r, double tau) { return r * tau / std::sqrt(2.0); }},
  };
  int legend = 0;
  for (const auto& l : lines) {
    if (!l.term->value) continue;
    o << "<polyline fill='none' stroke='" << l.color << "' stroke-dasharray='6 4' points='";
    for (int i = 0; i <= 40; ++i) {
      const double tau = x0 * std::pow(x1 / x0, i / 40.0);
      const double s = l.sigma(*l.term->value, tau);
      if (s > 0) o << f.px(tau) << ',' << f.py(s) << ' ';
    }
    o << "'/>\n";
    o << "<text x='" << kW - kR - 150 << "' y='" << kT + 20 + 16 * legend++ << "' font-size='12' fill='" << l.color
      << "'>" << l.name << " = " << num(*l.term->value) << ' ' << esc(l.term->unit) << "</text>\n";
  }
  // The paper's polynomial fit and its segment middles (tau_cp on the flat one).
  if (t.paper.ok) {
    o << "<polyline fill='none' stroke='#ff7f0e' stroke-width='1.5' points='";
    for (int i = 0; i <= 80; ++i) {
      const double lx = std::log10(x0) + (std::log10(x1) - std::log10(x0)) * i / 80.0;
      double ly = 0;
      for (int k = 4; k >= 0; --k) ly = ly * lx + t.paper.coef[static_cast<std::size_t>(k)];
      o << f.px(std::pow(10.0, lx)) << ',' << f.py(std::pow(10.0, ly)) << ' ';
    }
    o << "'/>\n";
    for (const auto& s : t.paper.segments) {
      o << "<circle cx='" << f.px(s.tau_mid_s) << "' cy='" << f.py(s.sigma_mid) << "' r='5' fill='none' stroke='#ff7f0e'"
        << " stroke-width='2'/><text x='" << f.px(s.tau_mid_s) + 7 << "' y='" << f.py(s.sigma_mid) - 7
        << "' font-size='11' fill='#ff7f0e'>" << s.term << " slope " << num(s.slope) << "</text>\n";
    }
    for (double ti : t.paper.inflection_tau_s)
      o << "<line x1='" << f.px(ti) << "' y1='" << kT << "' x2='" << f.px(ti) << "' y2='" << kH - kB
        << "' stroke='#ff7f0e' stroke-dasharray='2 4'/>\n";
  }
  // Measured points with their confidence bounds.
  for (const auto& p : v) {
    const double x = f.px(p.tau_s);
    if (p.lo > 0 && p.hi > 0)
      o << "<line x1='" << x << "' y1='" << f.py(p.lo) << "' x2='" << x << "' y2='" << f.py(p.hi)
        << "' stroke='#444'/>\n";
    o << "<circle cx='" << x << "' cy='" << f.py(p.dev) << "' r='2.5' fill='black'/>\n";
  }
  o << "</g>\n";
  if (t.tau_cp_s && t.B.value)
    o << "<text x='" << kL + 10 << "' y='" << kH - kB - 10 << "' font-size='12' fill='#ff7f0e'>paper: tau_cp = "
      << num(*t.tau_cp_s) << " s, B = sigma(tau_cp)/0.664 = " << num(*t.B.value) << ' ' << esc(unit) << "</text>\n";
  o << "</svg>\n";
  return o.str();
}

std::string psd_svg(const Psd& p, std::span<const Peak> peaks, const std::string& title, const std::string& unit) {
  std::ostringstream o;
  o << head();
  double ylo = std::numeric_limits<double>::max(), yhi = -ylo;
  for (std::size_t k = 1; k < p.psd.size(); ++k)
    if (p.psd[k] > 0) {
      const double db = 10 * std::log10(p.psd[k]);
      ylo = std::min(ylo, db);
      yhi = std::max(yhi, db);
    }
  if (p.psd.size() < 3 || ylo > yhi) {
    o << "<text x='40' y='60'>no spectrum</text></svg>\n";
    return o.str();
  }
  const Frame f(p.f_hz[1], p.f_hz.back(), ylo, yhi, false);
  o << f.grid("frequency, Hz", "PSD, dB re 1 " + unit + "^2/Hz", title);
  o << "<polyline fill='none' stroke='#1f77b4' points='";
  // At most ~2000 vertices: keep the maximum of each pixel column so peaks stay visible.
  const std::size_t n = p.psd.size(), stride = std::max<std::size_t>(1, n / 2000);
  for (std::size_t k = 1; k < n; k += stride) {
    double mx = 0;
    std::size_t at = k;
    for (std::size_t j = k; j < std::min(n, k + stride); ++j)
      if (p.psd[j] > mx) mx = p.psd[j], at = j;
    if (mx > 0) o << f.px(p.f_hz[at]) << ',' << f.py(10 * std::log10(mx)) << ' ';
  }
  o << "'/>\n";
  for (const auto& pk : peaks)
    if (pk.f_hz > 0 && pk.psd > 0)
      o << "<circle cx='" << f.px(pk.f_hz) << "' cy='" << f.py(10 * std::log10(pk.psd)) << "' r='4' fill='none' "
        << "stroke='#d62728'/><text x='" << f.px(pk.f_hz) + 5 << "' y='" << f.py(10 * std::log10(pk.psd)) - 6
        << "' font-size='11' fill='#d62728'>" << num(pk.f_hz) << " Hz</text>\n";
  o << "</svg>\n";
  return o.str();
}

}  // namespace rig::report
