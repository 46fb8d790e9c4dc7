#include "rig/report/svg.hpp"

#include "rig/core/markup.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace rig::report {

std::string html_escape(std::string_view s) { return markup_escape(s); }

std::string fmt_num(double v, int sig) {
  if (!std::isfinite(v)) return "\xE2\x80\x94";  // em dash
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", sig, v);
  return buf;
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Margins of the plot area inside the SVG (room for tick labels and axis titles).
constexpr double kLeft = 78, kRight = 18, kTop = 30, kBottom = 48;

// One axis: data range -> pixel range, linear or log10.
struct Axis {
  bool log = false;
  double lo = 0, hi = 1;        // in data units (log axes: positive)
  double p0 = 0, p1 = 1;        // pixels for lo and hi
  double t(double v) const { return log ? std::log10(v) : v; }
  bool usable(double v) const { return std::isfinite(v) && (!log || v > 0); }
  double px(double v) const { return p0 + (t(v) - t(lo)) / (t(hi) - t(lo)) * (p1 - p0); }
};

struct Range {
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
  void add(double v, bool log) {
    if (!std::isfinite(v) || (log && v <= 0)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool empty() const { return !(lo <= hi); }
};

// Linear: widen to "nice" tick multiples. Log: widen to whole decades (at least one).
void nice_range(Range& r, bool log) {
  if (r.empty()) {
    r.lo = log ? 1 : 0;
    r.hi = log ? 10 : 1;
    return;
  }
  if (log) {  // widen to the nearest 1-2-5 values, keeping at least a factor of 10
    const double dl = std::pow(10.0, std::floor(std::log10(r.lo) + 1e-9));
    double lo = dl;
    for (double m : {2.0, 5.0})
      if (m * dl <= r.lo * (1 + 1e-9)) lo = m * dl;
    const double dh = std::pow(10.0, std::floor(std::log10(r.hi) - 1e-9));
    double hi = 10 * dh;
    for (double m : {5.0, 2.0, 1.0})
      if (m * dh >= r.hi * (1 - 1e-9)) hi = m * dh;
    if (hi < lo * 10) hi = lo * 10;
    r.lo = lo;
    r.hi = hi;
    return;
  }
  if (r.hi == r.lo) {
    const double d = r.lo == 0 ? 1 : std::abs(r.lo) * 0.1;
    r.lo -= d;
    r.hi += d;
  }
  const double span = r.hi - r.lo;
  const double pad = span * 0.04;
  r.lo -= r.lo == 0 ? 0 : pad;
  r.hi += pad;
}

double nice_step(double span) {
  const double raw = span / 6;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * mag >= raw) return m * mag;
  return 10 * mag;
}

std::string n2(double v) {  // pixel coordinates
  char buf[24];
  std::snprintf(buf, sizeof buf, "%.1f", v);
  return buf;
}

// A tick label such as 10⁻⁶ written as "10" + raised exponent.
std::string decade_label(int e) {
  return "10<tspan dy=\"-6\" font-size=\"9\">" + std::to_string(e) + "</tspan>";
}

std::string tick_label(double v, double step) {
  if (std::abs(v) < step * 1e-6) return "0";
  const double a = std::abs(v);
  if (a >= 1e5 || a < 1e-3) return fmt_num(v, 3);
  // As many decimals as the step needs to be exact (a 0.0025 step needs 4, not 3).
  int dec = 0;
  while (dec < 9) {
    const double scaled = step * std::pow(10.0, dec);
    if (std::abs(scaled - std::round(scaled)) < 1e-6 * std::max(1.0, scaled)) break;
    ++dec;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", dec, v);
  return buf;
}

// Keeps at most ~2 points per pixel column (min and max) so a long record stays small.
void decimate(const Axis& ax, const std::vector<double>& x, const std::vector<double>& y, std::vector<double>& ox,
              std::vector<double>& oy) {
  const std::size_t n = std::min(x.size(), y.size());
  const double cols = std::abs(ax.p1 - ax.p0);
  if (n <= static_cast<std::size_t>(cols * 4)) {
    ox.assign(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(n));
    oy.assign(y.begin(), y.begin() + static_cast<std::ptrdiff_t>(n));
    return;
  }
  long col = std::numeric_limits<long>::min();
  std::size_t imin = 0, imax = 0;
  auto flush = [&] {
    if (col == std::numeric_limits<long>::min()) return;
    const std::size_t a = std::min(imin, imax), b = std::max(imin, imax);
    ox.push_back(x[a]);
    oy.push_back(y[a]);
    if (b != a) {
      ox.push_back(x[b]);
      oy.push_back(y[b]);
    }
  };
  for (std::size_t i = 0; i < n; ++i) {
    if (!ax.usable(x[i]) || !std::isfinite(y[i])) {
      flush();
      col = std::numeric_limits<long>::min();
      ox.push_back(kNaN);
      oy.push_back(kNaN);
      continue;
    }
    const long c = std::lround(ax.px(x[i]));
    if (c != col) {
      flush();
      col = c;
      imin = imax = i;
    } else {
      if (y[i] < y[imin]) imin = i;
      if (y[i] > y[imax]) imax = i;
    }
  }
  flush();
}

class Writer {
 public:
  explicit Writer(const Plot& p) : p_(p) {}

  std::string run(std::vector<bool>* labelled, const char* style) {
    legend_rows();
    ranges();
    frame();
    grid_and_ticks();
    os_ << "<g clip-path=\"url(#clip-" << html_escape(p_.id) << ")\">\n";
    for (const RefLine& l : p_.lines) ref_line(l);
    for (const Series& s : p_.series) series(s);
    if (labelled) labelled->clear();
    // Every marker's circle is taken before any label is placed, so no label covers a point.
    for (const Marker& m : p_.markers)
      if (x_.usable(m.x) && y_.usable(m.y))
        labels_.push_back({x_.px(m.x) - 4, y_.px(m.y) - 4, x_.px(m.x) + 4, y_.px(m.y) + 4});
    for (const Marker& m : p_.markers) {
      const bool placed = marker(m);
      if (labelled) labelled->push_back(placed);
    }
    os_ << "</g>\n";
    legend();
    if (!has_data_)
      os_ << "<text x=\"" << n2((x_.p0 + x_.p1) / 2) << "\" y=\"" << n2((y_.p0 + y_.p1) / 2)
          << "\" text-anchor=\"middle\" class=\"nodata\">no data</text>\n";
    os_ << "</svg>\n";
    std::ostringstream head;
    head << "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\" data-plot=\"" << html_escape(p_.id)
         << "\" viewBox=\"0 0 " << p_.width << ' ' << total_h_ << "\" width=\"" << p_.width << "\" height=\""
         << total_h_ << "\" role=\"img\" aria-label=\"" << html_escape(p_.title) << "\">\n"
         << "<title>" << html_escape(p_.title) << "</title>\n"
         << (style ? std::string("<style>") + style + "</style>\n" : std::string())
         << "<defs><clipPath id=\"clip-" << html_escape(p_.id) << "\"><rect x=\"" << n2(kLeft) << "\" y=\""
         << n2(kTop) << "\" width=\"" << n2(x_.p1 - x_.p0) << "\" height=\"" << n2(y_.p0 - y_.p1)
         << "\"/></clipPath></defs>\n";
    return head.str() + os_.str();
  }

 private:
  void legend_rows() {
    double x = 0;
    rows_ = 0;
    for (const Series& s : p_.series) {
      if (s.label.empty()) continue;
      const double w = item_width(s.label);
      if (rows_ == 0 || x + w > p_.width - kLeft - kRight) {
        ++rows_;
        x = 0;
      }
      x += w;
    }
    total_h_ = p_.height + rows_ * 16;
  }
  static double item_width(const std::string& label) { return 40 + 6.9 * static_cast<double>(label.size()); }

  void ranges() {
    Range rx, ry;
    for (const Series& s : p_.series) {
      if (!s.sets_range) continue;
      const std::size_t n = std::min(s.x.size(), s.y.size());
      for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i]) || (p_.log_x && s.x[i] <= 0) ||
            (p_.log_y && s.y[i] <= 0))
          continue;
        has_data_ = true;
        rx.add(s.x[i], p_.log_x);
        if (s.style != Series::Style::band) ry.add(s.y[i], p_.log_y);
        if (i < s.y_lo.size()) ry.add(s.y_lo[i], p_.log_y);
        if (i < s.y_hi.size()) ry.add(s.y_hi[i], p_.log_y);
      }
    }
    for (const RefLine& l : p_.lines) (l.vertical ? rx : ry).add(l.at, l.vertical ? p_.log_x : p_.log_y);
    for (const Marker& m : p_.markers) {
      rx.add(m.x, p_.log_x);
      ry.add(m.y, p_.log_y);
    }
    if (p_.x_range) {  // the caller's window; y still from the data inside it
      rx.lo = p_.x_range->first;
      rx.hi = p_.x_range->second;
      ry = Range{};
      for (const Series& s : p_.series) {
        if (!s.sets_range) continue;
        for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
          if (!(s.x[i] >= rx.lo && s.x[i] <= rx.hi)) continue;
          if (s.style != Series::Style::band) ry.add(s.y[i], p_.log_y);
          if (i < s.y_lo.size()) ry.add(s.y_lo[i], p_.log_y);
          if (i < s.y_hi.size()) ry.add(s.y_hi[i], p_.log_y);
        }
      }
      for (const RefLine& l : p_.lines)
        if (!l.vertical) ry.add(l.at, p_.log_y);
    }
    nice_range(rx, p_.log_x);
    nice_range(ry, p_.log_y);
    x_ = Axis{p_.log_x, rx.lo, rx.hi, kLeft, p_.width - kRight};
    y_ = Axis{p_.log_y, ry.lo, ry.hi, p_.height - kBottom, kTop};
  }

  void frame() {
    os_ << "<text x=\"" << n2(kLeft) << "\" y=\"18\" class=\"ptitle\">" << html_escape(p_.title) << "</text>\n";
    os_ << "<rect x=\"" << n2(kLeft) << "\" y=\"" << n2(kTop) << "\" width=\"" << n2(x_.p1 - x_.p0)
        << "\" height=\"" << n2(y_.p0 - y_.p1) << "\" class=\"area\"/>\n";
    os_ << "<text x=\"" << n2((x_.p0 + x_.p1) / 2) << "\" y=\"" << n2(p_.height - 8)
        << "\" text-anchor=\"middle\" class=\"alabel\">" << html_escape(p_.x_label) << "</text>\n";
    os_ << "<text transform=\"translate(14," << n2((y_.p0 + y_.p1) / 2)
        << ") rotate(-90)\" text-anchor=\"middle\" class=\"alabel\">" << html_escape(p_.y_label) << "</text>\n";
  }

  void grid_and_ticks() {
    ticks(x_, true);
    ticks(y_, false);
  }

  void ticks(const Axis& a, bool is_x) {
    auto line = [&](double v, bool major) {
      const double p = a.px(v);
      if (is_x)
        os_ << "<line x1=\"" << n2(p) << "\" y1=\"" << n2(y_.p1) << "\" x2=\"" << n2(p) << "\" y2=\"" << n2(y_.p0)
            << "\" class=\"" << (major ? "grid" : "grid minor") << "\"/>\n";
      else
        os_ << "<line x1=\"" << n2(x_.p0) << "\" y1=\"" << n2(p) << "\" x2=\"" << n2(x_.p1) << "\" y2=\"" << n2(p)
            << "\" class=\"" << (major ? "grid" : "grid minor") << "\"/>\n";
    };
    auto label = [&](double v, const std::string& text) {
      const double p = a.px(v);
      if (is_x)
        os_ << "<text x=\"" << n2(p) << "\" y=\"" << n2(y_.p0 + 16) << "\" text-anchor=\"middle\" class=\"tick\">"
            << text << "</text>\n";
      else
        os_ << "<text x=\"" << n2(x_.p0 - 6) << "\" y=\"" << n2(p + 4) << "\" text-anchor=\"end\" class=\"tick\">"
            << text << "</text>\n";
    };
    if (a.log) {
      const int e0 = static_cast<int>(std::floor(std::log10(a.lo) + 1e-9));
      const int e1 = static_cast<int>(std::floor(std::log10(a.hi) + 1e-9));
      const int every = std::max(1, (e1 - e0 + 7) / 8);  // at most ~8 labelled decades
      auto inside = [&](double v) { return v >= a.lo * (1 - 1e-9) && v <= a.hi * (1 + 1e-9); };
      for (int e = e0; e <= e1; ++e) {
        const double d = std::pow(10.0, e);
        if (inside(d)) {
          line(d, true);
          if ((e - e0) % every == 0) label(d, decade_label(e));
        }
        if (e1 - e0 <= 6)
          for (int m = 2; m <= 9; ++m)
            if (inside(m * d)) line(m * d, false);
      }
      return;
    }
    const double step = nice_step(a.hi - a.lo);
    for (double v = std::ceil(a.lo / step - 1e-9) * step; v <= a.hi + step * 1e-9; v += step) {
      line(v, true);
      label(v, tick_label(v, step));
    }
  }

  void ref_line(const RefLine& l) {
    const Axis& a = l.vertical ? x_ : y_;
    if (!a.usable(l.at)) return;
    const double p = a.px(l.at);
    if (l.vertical) {
      os_ << "<line x1=\"" << n2(p) << "\" y1=\"" << n2(y_.p1) << "\" x2=\"" << n2(p) << "\" y2=\"" << n2(y_.p0)
          << "\" stroke=\"" << html_escape(l.color) << "\" class=\"ref\"/>\n";
      os_ << "<text x=\"" << n2(p + 4) << "\" y=\"" << n2(y_.p1 + 12) << "\" class=\"reftext\" fill=\""
          << html_escape(l.color) << "\">" << html_escape(l.text) << "</text>\n";
    } else {
      os_ << "<line x1=\"" << n2(x_.p0) << "\" y1=\"" << n2(p) << "\" x2=\"" << n2(x_.p1) << "\" y2=\"" << n2(p)
          << "\" stroke=\"" << html_escape(l.color) << "\" class=\"ref\"/>\n";
      os_ << "<text x=\"" << n2(x_.p1 - 4) << "\" y=\"" << n2(p - 4) << "\" text-anchor=\"end\" class=\"reftext\" fill=\""
          << html_escape(l.color) << "\">" << html_escape(l.text) << "</text>\n";
    }
  }

  // The area between y_lo and y_hi as one polygon per finite run: upper edge left to
  // right, lower edge back (the x axis is monotonic for an envelope).
  void band(const Series& s) {
    const std::size_t n = std::min({s.x.size(), s.y_lo.size(), s.y_hi.size()});
    std::size_t i = 0;
    while (i < n) {
      std::size_t j = i;
      while (j < n && x_.usable(s.x[j]) && y_.usable(s.y_lo[j]) && y_.usable(s.y_hi[j])) ++j;
      if (j > i) {
        std::string pts;
        for (std::size_t k = i; k < j; ++k) pts += n2(x_.px(s.x[k])) + "," + n2(y_.px(s.y_hi[k])) + " ";
        for (std::size_t k = j; k-- > i;) pts += n2(x_.px(s.x[k])) + "," + n2(y_.px(s.y_lo[k])) + " ";
        os_ << "<polygon fill=\"" << html_escape(s.color) << "\" fill-opacity=\"0.55\" stroke=\"none\" points=\"" << pts << "\"/>\n";
      }
      i = j + 1;
    }
  }

  void series(const Series& s) {
    const std::string color = html_escape(s.color);
    if (s.style == Series::Style::band) {
      band(s);
      return;
    }
    if (s.style != Series::Style::markers) {
      std::vector<double> xs, ys;
      decimate(x_, s.x, s.y, xs, ys);
      std::string pts;
      auto flush = [&] {
        if (pts.empty()) return;
        os_ << "<polyline fill=\"none\" stroke=\"" << color << "\" stroke-width=\"" << s.width << "\""
            << (s.dashed ? " stroke-dasharray=\"6 4\"" : "") << " points=\"" << pts << "\"/>\n";
        pts.clear();
      };
      for (std::size_t i = 0; i < xs.size(); ++i) {
        if (!x_.usable(xs[i]) || !y_.usable(ys[i])) {
          flush();
          continue;
        }
        pts += n2(x_.px(xs[i])) + "," + n2(y_.px(ys[i])) + " ";
      }
      flush();
    }
    // Markers and error bars: at most one per 2 px column, so a dense series stays readable and small.
    const std::size_t n = std::min(s.x.size(), s.y.size());
    double last_px = -1e9;
    for (std::size_t i = 0; i < n; ++i) {
      if (!x_.usable(s.x[i])) continue;
      const double px = x_.px(s.x[i]);
      if (std::abs(px - last_px) < 2.0) continue;
      last_px = px;
      if (i < s.y_lo.size() && i < s.y_hi.size() && y_.usable(s.y_lo[i]) && y_.usable(s.y_hi[i]))
        os_ << "<line x1=\"" << n2(px) << "\" y1=\"" << n2(y_.px(s.y_lo[i])) << "\" x2=\"" << n2(px) << "\" y2=\""
            << n2(y_.px(s.y_hi[i])) << "\" stroke=\"" << color << "\" class=\"ebar\"/>\n";
      if (s.style != Series::Style::line && y_.usable(s.y[i]))
        os_ << "<circle cx=\"" << n2(px) << "\" cy=\"" << n2(y_.px(s.y[i])) << "\" r=\"2.6\" fill=\"" << color
            << "\"/>\n";
    }
  }

  // True when the marker's text label was placed.
  bool marker(const Marker& m) {
    if (!x_.usable(m.x) || !y_.usable(m.y)) return false;
    if (m.x < x_.lo || m.x > x_.hi) return false;  // outside a caller's x window
    const double px = x_.px(m.x), py = y_.px(m.y);
    const bool left = px > (x_.p0 + x_.p1) / 2 + (x_.p1 - x_.p0) * 0.3;  // near the right edge: label to the left
    os_ << "<circle cx=\"" << n2(px) << "\" cy=\"" << n2(py) << "\" r=\"3.5\" fill=\"none\" stroke=\""
        << html_escape(m.color) << "\" stroke-width=\"1.5\"/>\n";
    // Label box: the preferred place first, then shifted 13 px at a time up and down, on
    // either side of the point, until it overlaps no earlier label (close PSD peaks);
    // dropped if no free place is found (the circle stays).
    const double w = 7.0 * static_cast<double>(m.text.size()), h = 12;
    const double y_pref = m.below ? std::min(py + 15, y_.p0 - 4) : std::max(py - 6, y_.p1 + 10);
    for (int k = 0; k < 16; ++k) {
      const double dy = (k / 2 % 2 == 0 ? -1.0 : 1.0) * 13.0 * ((k / 4) + (k / 2 % 2 == 0 ? 0 : 1)) * (m.below ? -1 : 1);
      const bool on_left = (k % 2 == 0) == left;
      const double y = y_pref + dy;
      if (y < y_.p1 + 10 || y > y_.p0 - 2) continue;
      const double x0 = on_left ? px - 6 - w : px + 6;
      if (x0 < x_.p0 || x0 + w > x_.p1 + kRight) continue;
      const Box b{x0, y - h, x0 + w, y};
      if (std::any_of(labels_.begin(), labels_.end(), [&](const Box& o) { return b.overlaps(o); })) continue;
      labels_.push_back(b);
      os_ << "<text x=\"" << n2(on_left ? px - 6 : px + 6) << "\" y=\"" << n2(y) << "\" class=\"mark\""
          << (on_left ? " text-anchor=\"end\"" : "") << " fill=\"" << html_escape(m.color) << "\">"
          << html_escape(m.text) << "</text>\n";
      return true;
    }
    return false;
  }

  void legend() {
    double x = kLeft, y = p_.height + 4;
    int row = 0;
    for (const Series& s : p_.series) {
      if (s.label.empty()) continue;
      const double w = item_width(s.label);
      if (row == 0 || x + w > p_.width - kRight) {
        ++row;
        x = kLeft;
        y = p_.height - 4 + row * 16;
      }
      if (s.style == Series::Style::band)
        os_ << "<rect x=\"" << n2(x) << "\" y=\"" << n2(y - 9) << "\" width=\"24\" height=\"10\" fill=\""
            << html_escape(s.color) << "\" fill-opacity=\"0.55\"/>\n";
      else
        os_ << "<line x1=\"" << n2(x) << "\" y1=\"" << n2(y - 4) << "\" x2=\"" << n2(x + 24) << "\" y2=\"" << n2(y - 4)
            << "\" stroke=\"" << html_escape(s.color) << "\" stroke-width=\"2\""
            << (s.dashed ? " stroke-dasharray=\"6 4\"" : "") << "/>\n";
      os_ << "<text x=\"" << n2(x + 28) << "\" y=\"" << n2(y) << "\" class=\"legend\">" << html_escape(s.label)
          << "</text>\n";
      x += w;
    }
  }

  const Plot& p_;
  std::ostringstream os_;
  Axis x_, y_;
  int rows_ = 0;
  int total_h_ = 0;
  bool has_data_ = false;
  struct Box {
    double x0, y0, x1, y1;
    bool overlaps(const Box& o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
  };
  std::vector<Box> labels_;  // marker labels placed so far
};

}  // namespace

const char* svg_css() {
  return R"CSS(
svg.plot { max-width: 100%; height: auto; display: block; font-family: "DejaVu Sans", Arial, sans-serif; }
svg .area { fill: #fff; stroke: #333; stroke-width: 1; }
svg .grid { stroke: #dcdfe3; stroke-width: 1; } svg .grid.minor { stroke: #eff1f3; }
svg .tick { font-size: 11px; fill: #333; } svg .alabel { font-size: 12px; fill: #222; }
svg .ptitle { font-size: 13px; font-weight: 700; fill: #111; } svg .legend { font-size: 11px; fill: #222; }
svg .ref { stroke-width: 1.2; stroke-dasharray: 4 3; } svg .reftext { font-size: 11px; }
svg .mark { font-size: 11px; font-weight: 600; } svg .ebar { stroke-width: 1; opacity: .7; }
svg .nodata { font-size: 14px; fill: #999; }
)CSS";
}

std::string to_svg(const Plot& p, std::vector<bool>* labelled) { return Writer(p).run(labelled, nullptr); }

std::string to_svg_file(const Plot& p) {
  return "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n" + Writer(p).run(nullptr, svg_css());
}

}  // namespace rig::report
