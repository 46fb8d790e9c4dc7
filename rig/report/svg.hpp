// Small SVG chart writer for report.html: line/marker series with optional error bars,
// linear or log axes with ticks and grid, reference lines, labelled points and a legend.
// Output is a standalone <svg> element; every text is escaped.
#pragma once
#include <string>
#include <string_view>
#include <vector>

namespace rig::report {

// Escapes & < > " ' for HTML text, attributes and SVG.
std::string html_escape(std::string_view s);
// A number for people: `sig` significant digits, "—" for NaN/inf.
std::string fmt_num(double v, int sig = 4);

struct Series {
  enum class Style { line, markers, line_markers };
  std::string label;  // legend text; empty = not in the legend
  std::vector<double> x, y;
  std::vector<double> y_lo, y_hi;  // optional error bars, same length as y
  std::string color = "#1f77b4";
  Style style = Style::line;
  bool dashed = false;
  double width = 1.5;
  bool sets_range = true;  // false for fitted curves: the data alone decide the axes
};

// A labelled point (a PSD peak, a settling time).
struct Marker {
  double x = 0, y = 0;
  std::string text;
  std::string color = "#d62728";
  bool below = false;  // label under the point (to keep two labels apart)
};

// A horizontal or vertical reference line across the plot (τ_ср, the 0.5 level, a limit).
struct RefLine {
  bool vertical = true;
  double at = 0;
  std::string text;
  std::string color = "#555";
};

struct Plot {
  std::string id;  // unique in the page; also written as data-plot="id"
  std::string title, x_label, y_label;
  bool log_x = false, log_y = false;
  std::vector<Series> series;
  std::vector<Marker> markers;
  std::vector<RefLine> lines;
  int width = 900, height = 400;
};

std::string to_svg(const Plot& p);

}  // namespace rig::report
