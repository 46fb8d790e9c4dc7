// Small SVG chart writer for report.html: line/marker series with optional error bars,
// linear or log axes with ticks and grid, reference lines, labelled points and a legend.
// Output is a standalone <svg> element; every text is escaped.
#pragma once
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace rig::report {

// Escapes & < > " ' for HTML text, attributes and SVG.
std::string html_escape(std::string_view s);
// A number for people: `sig` significant digits, "—" for NaN/inf.
std::string fmt_num(double v, int sig = 4);

struct Series {
  // band: the area between y_lo and y_hi filled (a min/max envelope); y is not drawn.
  enum class Style { line, markers, line_markers, band };
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
  // The x axis range instead of the data's (e.g. a step response scaled to its settling);
  // what lies outside is clipped.
  std::optional<std::pair<double, double>> x_range;
};

// The <svg> element for a page that carries svg_css(). `labelled`, when given, receives for
// each marker whether its text label was placed (a label with no free place is dropped, the
// circle stays), so a caption can name exactly the labelled points.
std::string to_svg(const Plot& p, std::vector<bool>* labelled = nullptr);
// The same as a standalone .svg file: the style rules inside it.
std::string to_svg_file(const Plot& p);
// The CSS rules the plots' classes need (report.html carries them once).
const char* svg_css();

}  // namespace rig::report
