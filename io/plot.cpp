#include "io/plot.hpp"

#include <plstream.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>

#include "host/error.hpp"
#include "host/files.hpp"

namespace talus {

namespace {

namespace fs = std::filesystem;
using sim2real::Channel;
using sim2real::Run;
using sim2real::TimeSeries;

// ---- layout, in pixels ----------------------------------------------------------------------
// every length below is a multiple of the text height, so labels never collide with ticks
constexpr double kTextPx = 14.0;        // character height [px]: legible at 1000-1500 px widths
constexpr double kLeftEm = 9.0;         // y tick labels (horizontal) and a y label of two lines
constexpr double kRightEm = 2.0;        // room for the last x tick label
constexpr double kBottomEm = 4.5;       // x tick labels and the x label
constexpr double kTopEm = 0.8;          // above the legend
constexpr double kGapEm = 1.0;          // between stacked panels (they share the x axis)
constexpr double kTitleEm = 2.2;        // a panel title above its panel
constexpr double kLegendRowEm = 2.0;    // one legend row
constexpr std::size_t kLegendColumns = 4;  // entries per legend row
constexpr double kYLabelEm = 7.6;          // y label distance from the plot box [text heights]
constexpr double kYLabelLineEm =
    1.7;  // between the two lines of a split y label (glyphs stand 1.4 high)
constexpr double kXLabelEm = 3.2;       // x label distance below the plot box [text heights]
constexpr double kTitleDispEm = 0.8;    // panel title distance above the plot box
// a character's mean advance in text heights: DejaVu Sans, pngcairo's font, averages about 0.55
// for lower-case text; 0.6 errs on the long side, so an estimated fit is a real one
constexpr double kCharWidthEm = 0.6;
// a y label may fill this fraction of its panel's height; beyond it, it is split, then scaled
constexpr double kYLabelFill = 0.92;
// the smallest scale a y label is drawn at (10 px of 14: still legible)
constexpr double kMinLabelScale = 0.7;

// the data extent gets this fraction of margin on each side (y always; x for markers and
// equal-aspect panels, whose points would otherwise sit half outside the box)
constexpr double kPadFraction = 0.05;

// image sizes write_png accepts [px]: below this the margins eat the plot, above it cairo's
// surface gets unreasonably large
constexpr int kMinPx = 200;
constexpr int kMaxPx = 10000;

// line widths in PLplot units (pixels with pngcairo)
constexpr double kSeriesWidth = 2.0;
constexpr double kAxisWidth = 1.0;
constexpr double kOutlineWidth = 1.5;
// PLplot's built-in line style 3: 2 mm dashes, 2 mm gaps (pllsty; the legend uses the same)
constexpr PLINT kDashedStyle = 3;
constexpr PLINT kSolidStyle = 1;
// the marker of series with markers: a filled circle, drawn as text at the point
constexpr const char* kMarker = "\u25cf";

// cmap0 slots: PLplot paints the background with slot 0; series colours start at kFirstColour
constexpr PLINT kBackground = 0;
constexpr PLINT kInk = 1;
constexpr PLINT kShade = 2;
constexpr PLINT kFirstColour = 3;

// PLplot keeps its stream table, current stream and driver table in process-wide state: one
// figure at a time is drawn
std::mutex& plplot_mutex() {
  static std::mutex m;
  return m;
}

bool finite_positive(double v) { return std::isfinite(v) && v > 0.0; }

// data value -> PLplot world coordinate (PLplot's log axes take log10 of the data)
double to_world(double v, bool log) {
  if (!log) return std::isfinite(v) ? v : std::numeric_limits<double>::quiet_NaN();
  return finite_positive(v) ? std::log10(v) : std::numeric_limits<double>::quiet_NaN();
}

// running min/max of world coordinates
struct Extent {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double w) {
    if (!std::isfinite(w)) return;
    lo = std::min(lo, w);
    hi = std::max(hi, w);
  }
  bool empty() const { return !(lo <= hi); }
};

// world extent -> a data range with margins; never empty nor zero-width
Range finish_range(Extent e, bool log, double pad_fraction) {
  if (e.empty()) {
    e.lo = 0.0;  // [0, 1] linear, [1, 10] log
    e.hi = 1.0;
  }
  double span = e.hi - e.lo;
  if (span <= 1e-12 * std::max(1.0, std::abs(e.lo))) {
    // one value: half a unit (half a decade on log axes) around it
    double half = log ? 0.5 : 0.5 * std::max(1.0, std::abs(e.lo));
    e.lo -= half;
    e.hi += half;
    span = e.hi - e.lo;
  }
  e.lo -= pad_fraction * span;
  e.hi += pad_fraction * span;
  if (log) return {std::pow(10.0, e.lo), std::pow(10.0, e.hi)};
  return {e.lo, e.hi};
}

bool has_markers(const Panel& p) {
  return std::any_of(p.series.begin(), p.series.end(), [](const Series& s) { return s.markers; });
}

// the legend: one entry per distinct label, in order of appearance
std::vector<const Series*> legend_entries(const Figure& f) {
  std::vector<const Series*> out;
  for (const Panel& p : f.panels)
    for (const Series& s : p.series) {
      if (s.label.empty()) continue;
      bool seen = std::any_of(out.begin(), out.end(), [&](const Series* o) { return o->label == s.label; });
      if (!seen) out.push_back(&s);
    }
  return out;
}

std::size_t legend_rows(const Figure& f) {
  std::size_t n = legend_entries(f).size();
  return (n + kLegendColumns - 1) / kLegendColumns;
}

// plot boxes of all panels in pixels, before equal-aspect range adjustments
std::vector<PanelGeometry> boxes(const Figure& f, int width_px, int height_px) {
  const std::size_t n = f.panels.size();
  std::vector<PanelGeometry> out(n);
  if (n == 0) return out;
  const double top = kTextPx * (kTopEm + kLegendRowEm * static_cast<double>(legend_rows(f)));
  const double bottom = height_px - kTextPx * kBottomEm;
  double fixed = 0.0;  // vertical pixels taken by gaps and titles between top and bottom
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0) fixed += kTextPx * kGapEm;
    if (!f.panels[i].title.empty()) fixed += kTextPx * kTitleEm;
  }
  const double panel_h = std::max(1.0, (bottom - top - fixed) / static_cast<double>(n));
  double y = top;
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0) y += kTextPx * kGapEm;
    if (!f.panels[i].title.empty()) y += kTextPx * kTitleEm;
    out[i].left = kTextPx * kLeftEm;
    out[i].right = std::max(out[i].left + 1.0, width_px - kTextPx * kRightEm);
    out[i].top = y;
    out[i].bottom = y + panel_h;
    out[i].log_x = f.log_x;
    out[i].log_y = f.panels[i].log_y;
    y += panel_h;
  }
  return out;
}

// x extent over every panel's series and areas, in world coordinates
Extent x_extent(const Figure& f) {
  Extent e;
  for (const Panel& p : f.panels) {
    for (const Series& s : p.series)
      for (double x : s.x) e.add(to_world(x, f.log_x));
    for (const Area& a : p.areas)
      for (double x : a.x) e.add(to_world(x, f.log_x));
  }
  return e;
}

Extent y_extent(const Panel& p) {
  Extent e;
  for (const Series& s : p.series)
    for (double y : s.y) e.add(to_world(y, p.log_y));
  for (const Area& a : p.areas)
    for (double y : a.y) e.add(to_world(y, p.log_y));
  return e;
}

// widens `r` (linear) about its centre to `span`
Range widened(Range r, double span) {
  double mid = 0.5 * (r.lo + r.hi);
  return {mid - 0.5 * span, mid + 0.5 * span};
}

// the full layout: boxes plus the data ranges each box spans
std::vector<PanelGeometry> layout(const Figure& f, int width_px, int height_px) {
  std::vector<PanelGeometry> g = boxes(f, width_px, height_px);
  bool pad_x = std::any_of(f.panels.begin(), f.panels.end(),
                           [](const Panel& p) { return has_markers(p) || p.equal_aspect; });
  Range x = f.x_range ? *f.x_range : finish_range(x_extent(f), f.log_x, pad_x ? kPadFraction : 0.0);
  std::vector<Range> y(f.panels.size());
  for (std::size_t i = 0; i < f.panels.size(); ++i)
    y[i] = f.panels[i].y_range ? *f.panels[i].y_range
                               : finish_range(y_extent(f.panels[i]), f.panels[i].log_y, kPadFraction);
  // equal aspect on linear axes: pixels per unit alike across and up; x is shared, so it is
  // widened first for every such panel, then each panel's y
  for (std::size_t i = 0; i < f.panels.size(); ++i) {
    if (!f.panels[i].equal_aspect || f.log_x || f.panels[i].log_y) continue;
    double w = g[i].right - g[i].left, h = g[i].bottom - g[i].top;
    double x_per_px = (x.hi - x.lo) / w, y_per_px = (y[i].hi - y[i].lo) / h;
    if (y_per_px > x_per_px) x = widened(x, y_per_px * w);
  }
  for (std::size_t i = 0; i < f.panels.size(); ++i) {
    if (f.panels[i].equal_aspect && !f.log_x && !f.panels[i].log_y) {
      double w = g[i].right - g[i].left, h = g[i].bottom - g[i].top;
      double x_per_px = (x.hi - x.lo) / w;
      if (x_per_px * h > y[i].hi - y[i].lo) y[i] = widened(y[i], x_per_px * h);
    }
    g[i].x = x;
    g[i].y = y[i];
  }
  return g;
}

// the cmap0 slot of every colour the figure uses, from kFirstColour on
std::vector<Rgb> palette(const Figure& f) {
  std::vector<Rgb> colours;
  auto add = [&](const Rgb& c) {
    if (std::find(colours.begin(), colours.end(), c) == colours.end()) colours.push_back(c);
  };
  for (const Panel& p : f.panels) {
    for (const Series& s : p.series) add(s.colour);
    for (const Area& a : p.areas) {
      add(a.fill);
      add(a.outline);
    }
  }
  return colours;
}

PLINT slot(const std::vector<Rgb>& colours, const Rgb& c) {
  auto it = std::find(colours.begin(), colours.end(), c);
  return kFirstColour + static_cast<PLINT>(it - colours.begin());
}

// is PLplot's pngcairo driver installed (plplot-driver-cairo)? asked before plinit, which would
// otherwise prompt on stdin for another device
bool have_pngcairo() {
  constexpr int kMaxDevices = 128;  // PLplot ships a few dozen drivers at most
  std::vector<const char*> menu(kMaxDevices, nullptr), names(kMaxDevices, nullptr);
  const char** menu_p = menu.data();
  const char** names_p = names.data();
  int n = kMaxDevices;
  ::plgDevs(&menu_p, &names_p, &n);
  for (int i = 0; i < n; ++i)
    if (names[i] && std::strcmp(names[i], "pngcairo") == 0) return true;
  return false;
}

// how data map to PLplot world coordinates on one axis, and how that axis is ticked. PLplot's log
// axes label decades only; a log axis spanning fewer than kFewDecades becomes a linear axis of
// log10(v / anchor) ticked at every doubling of `anchor` (50, 100, 200, 400 mm for the particle
// sizes) and labelled with data values by value_label
constexpr double kFewDecades = 2.0;
constexpr double kLog10Of2 = 0.30102999566398120;  // log10(2): one doubling on a log10 axis

struct AxisMap {
  bool log = false;
  bool doubling = false;
  double shift = 0.0;  // log10(anchor) when doubling

  double world(double v) const { return to_world(v, log) - shift; }
  // plbox options (after "bc" and "n" where wanted), major tick spacing and minor intervals
  std::string options() const { return doubling ? "sto" : log ? "stl" : "st"; }
  double tick() const { return doubling ? kLog10Of2 : 0.0; }
  PLINT minor() const { return doubling ? 1 : 0; }
};

AxisMap axis_map(bool log, const Range& r, double anchor) {
  AxisMap m;
  m.log = log;
  if (log && std::log10(r.hi / r.lo) < kFewDecades) {
    m.doubling = true;
    m.shift = std::log10(finite_positive(anchor) ? anchor : r.lo);
  }
  return m;
}

// smallest positive value among the x (or y) of the given series and areas
double smallest_positive(const std::vector<const std::vector<double>*>& columns) {
  double m = std::numeric_limits<double>::infinity();
  for (const std::vector<double>* c : columns)
    for (double v : *c)
      if (finite_positive(v)) m = std::min(m, v);
  return m;
}

// the shifts of doubling axes, read by value_label while plbox draws
struct LabelShifts {
  double x = 0.0, y = 0.0;
};

// a tick label of a doubling axis: the data value at the tick ("%g": 50, 100, 0.001)
void value_label(PLINT axis, PLFLT value, char* label, PLINT length, PLPointer data) {
  const auto* shifts = static_cast<const LabelShifts*>(data);
  const double shift = axis == PL_X_AXIS ? shifts->x : shifts->y;
  std::snprintf(label, static_cast<std::size_t>(length), "%g", std::pow(10.0, value + shift));
}

// text shown literally: PLplot reads '#' as its escape character ("##" is a plain '#')
std::string literal(const std::string& text) {
  std::string out;
  for (char c : text) {
    out += c;
    if (c == '#') out += '#';
  }
  return out;
}

// the world coordinates of one series, split at non-finite points into drawable runs
std::vector<std::pair<std::vector<PLFLT>, std::vector<PLFLT>>> pieces(const std::vector<double>& x,
                                                                      const std::vector<double>& y,
                                                                      const AxisMap& mx, const AxisMap& my) {
  std::vector<std::pair<std::vector<PLFLT>, std::vector<PLFLT>>> out(1);
  const std::size_t n = std::min(x.size(), y.size());
  for (std::size_t i = 0; i < n; ++i) {
    double wx = mx.world(x[i]), wy = my.world(y[i]);
    if (std::isfinite(wx) && std::isfinite(wy)) {
      out.back().first.push_back(wx);
      out.back().second.push_back(wy);
    } else if (!out.back().first.empty()) {
      out.emplace_back();
    }
  }
  if (out.back().first.empty()) out.pop_back();
  return out;
}

}  // namespace

YLabelLines y_label_lines(const std::string& label, double panel_px) {
  const auto length_px = [](const std::string& text) {
    return kCharWidthEm * kTextPx * static_cast<double>(text.size());
  };
  const double room = kYLabelFill * panel_px;
  YLabelLines out;
  out.lines = {label};
  // too long for the panel: the name, then its unit nearer the axis
  const std::size_t unit = label.rfind(" [");
  if (length_px(label) > room && unit != std::string::npos && unit > 0)
    out.lines = {label.substr(0, unit), label.substr(unit + 1)};
  double longest = 0.0;
  for (const std::string& line : out.lines) longest = std::max(longest, length_px(line));
  out.scale = longest > room && longest > 0.0 ? std::max(kMinLabelScale, room / longest) : 1.0;
  return out;
}

namespace {

void draw_panel(plstream& pls, const Figure& f, std::size_t index, const PanelGeometry& g,
                int width_px, int height_px, const std::vector<Rgb>& colours) {
  const Panel& p = f.panels[index];
  const bool bottom_panel = index + 1 == f.panels.size();
  std::vector<const std::vector<double>*> xs_all, ys_all;
  for (const Panel& q : f.panels)
    for (const Series& s : q.series) xs_all.push_back(&s.x);
  for (const Series& s : p.series) ys_all.push_back(&s.y);
  const AxisMap mx = axis_map(g.log_x, g.x, smallest_positive(xs_all));
  const AxisMap my = axis_map(g.log_y, g.y, smallest_positive(ys_all));
  // box in normalised device coordinates (origin bottom-left) and the world window
  pls.vpor(g.left / width_px, g.right / width_px, 1.0 - g.bottom / height_px, 1.0 - g.top / height_px);
  const double wx0 = mx.world(g.x.lo), wx1 = mx.world(g.x.hi);
  const double wy0 = my.world(g.y.lo), wy1 = my.world(g.y.hi);
  pls.wind(wx0, wx1, wy0, wy1);

  // grey intervals first, clipped to the window, full panel height
  pls.col0(kShade);
  for (const Range& r : p.shaded) {
    double a = std::max(std::min(wx0, wx1), mx.world(std::min(r.lo, r.hi)));
    double b = std::min(std::max(wx0, wx1), mx.world(std::max(r.lo, r.hi)));
    if (!(a < b)) continue;
    std::array<PLFLT, 4> xs{a, b, b, a}, ys{wy0, wy0, wy1, wy1};
    pls.fill(4, xs.data(), ys.data());
  }

  // filled areas, then their outlines
  for (const Area& a : p.areas) {
    for (const auto& [xs, ys] : pieces(a.x, a.y, mx, my)) {
      if (xs.size() < 3) continue;
      pls.col0(slot(colours, a.fill));
      pls.fill(static_cast<PLINT>(xs.size()), xs.data(), ys.data());
      pls.col0(slot(colours, a.outline));
      pls.width(kOutlineWidth);
      pls.lsty(kSolidStyle);
      pls.line(static_cast<PLINT>(xs.size()), xs.data(), ys.data());
    }
  }

  // series in order (later ones on top)
  for (const Series& s : p.series) {
    pls.col0(slot(colours, s.colour));
    pls.width(kSeriesWidth);
    pls.lsty(s.style == LineStyle::dashed ? kDashedStyle : kSolidStyle);
    for (const auto& [xs, ys] : pieces(s.x, s.y, mx, my)) {
      if (xs.size() >= 2) pls.line(static_cast<PLINT>(xs.size()), xs.data(), ys.data());
      if (s.markers) pls.string(static_cast<PLINT>(xs.size()), xs.data(), ys.data(), kMarker);
    }
  }

  // axes on top: numeric x labels only under the bottom panel (the x axis is shared);
  // y tick labels horizontal ("v")
  pls.col0(kInk);
  pls.width(kAxisWidth);
  pls.lsty(kSolidStyle);
  LabelShifts shifts{mx.shift, my.shift};
  pls.slabelfunc(value_label, &shifts);
  const std::string xopt = "bc" + mx.options() + (bottom_panel ? "n" : "");
  const std::string yopt = "bcnv" + my.options();
  pls.box(xopt.c_str(), mx.tick(), mx.minor(), yopt.c_str(), my.tick(), my.minor());
  pls.slabelfunc(nullptr, nullptr);
  // the y label, split and scaled to the panel's height so stacked panels' labels never meet
  const YLabelLines y_label = y_label_lines(p.y_label, g.bottom - g.top);
  pls.schr(0.0, y_label.scale);
  for (std::size_t k = 0; k < y_label.lines.size(); ++k) {
    // mtex measures its displacement in the current (scaled) character height
    const double disp = (kYLabelEm - kYLabelLineEm * static_cast<double>(k)) / y_label.scale;
    pls.mtex("l", disp, 0.5, 0.5, literal(y_label.lines[k]).c_str());
  }
  pls.schr(0.0, 1.0);
  if (!p.title.empty()) pls.mtex("t", kTitleDispEm, 0.5, 0.5, literal(p.title).c_str());
  if (bottom_panel) pls.mtex("b", kXLabelEm, 0.5, 0.5, literal(f.x_label).c_str());
}

// the legend above the top panel (and its title), kLegendColumns entries per row
void draw_legend(plstream& pls, const Figure& f, const PanelGeometry& top, int width_px, int height_px,
                 const std::vector<Rgb>& colours) {
  std::vector<const Series*> entries = legend_entries(f);
  if (entries.empty()) return;
  pls.vpor(top.left / width_px, top.right / width_px, 1.0 - top.bottom / height_px,
           1.0 - top.top / height_px);
  const PLINT n = static_cast<PLINT>(entries.size());
  std::vector<PLINT> opt(n), text_colours(n, kInk), line_colours(n), line_styles(n), symbol_colours(n),
      symbol_numbers(n, 1), box_colours(n, kBackground), box_patterns(n, 0);
  std::vector<PLFLT> line_widths(n, kSeriesWidth), symbol_scales(n, 1.0), box_scales(n, 1.0),
      box_line_widths(n, 1.0);
  std::vector<std::string> labels(n);
  std::vector<const char*> text(n), symbols(n, kMarker);
  for (PLINT i = 0; i < n; ++i) {
    const Series& s = *entries[i];
    opt[i] = PL_LEGEND_LINE | (s.markers ? PL_LEGEND_SYMBOL : 0);
    labels[i] = literal(s.label);
    text[i] = labels[i].c_str();
    line_colours[i] = symbol_colours[i] = slot(colours, s.colour);
    line_styles[i] = s.style == LineStyle::dashed ? kDashedStyle : kSolidStyle;
  }
  const PLINT columns = static_cast<PLINT>(std::min<std::size_t>(kLegendColumns, entries.size()));
  const PLINT rows = (n + columns - 1) / columns;
  // above the panel's title when it has one; offsets are fractions of the box height
  const double box_h = top.bottom - top.top;
  const double lift = f.panels.front().title.empty() ? 0.0 : kTextPx * kTitleEm / box_h;
  constexpr double kSampleWidth = 0.06;   // line sample length, fraction of the box width
  constexpr double kTextOffset = 0.8;     // sample to text [text heights]
  constexpr double kTextSpacing = 1.8;    // row pitch [text heights]
  PLFLT legend_w = 0.0, legend_h = 0.0;
  pls.legend(&legend_w, &legend_h, 0, PL_POSITION_OUTSIDE | PL_POSITION_TOP | PL_POSITION_VIEWPORT, 0.0,
             lift, kSampleWidth, kBackground, kInk, kSolidStyle, rows, columns, n, opt.data(),
             kTextOffset, 1.0, kTextSpacing, 0.0, text_colours.data(), text.data(), box_colours.data(),
             box_patterns.data(), box_scales.data(), box_line_widths.data(), line_colours.data(),
             line_styles.data(), line_widths.data(), symbol_colours.data(), symbol_scales.data(),
             symbol_numbers.data(), symbols.data());
}

// removes a file when the scope ends unless released (the temporary PNG on every failure path)
class RemoveOnExit {
 public:
  explicit RemoveOnExit(std::string path) : path_(std::move(path)) {}
  ~RemoveOnExit() {
    if (path_.empty()) return;
    std::error_code ec;
    fs::remove(path_, ec);
  }
  void release() { path_.clear(); }
  RemoveOnExit(const RemoveOnExit&) = delete;
  RemoveOnExit& operator=(const RemoveOnExit&) = delete;

 private:
  std::string path_;
};

// does the file start with the PNG signature?
bool looks_like_png(const std::string& path) {
  static constexpr std::array<unsigned char, 8> kSignature = {137, 'P', 'N', 'G', 13, 10, 26, 10};
  std::ifstream in(path, std::ios::binary);
  std::array<char, 8> head{};
  if (!in.read(head.data(), head.size())) return false;
  return std::memcmp(head.data(), kSignature.data(), kSignature.size()) == 0;
}

}  // namespace

// ---- figure -----------------------------------------------------------------------------------

double PanelGeometry::column(double x_data) const {
  double a = to_world(x.lo, log_x), b = to_world(x.hi, log_x);
  return left + (to_world(x_data, log_x) - a) / (b - a) * (right - left);
}

double PanelGeometry::row(double y_data) const {
  double a = to_world(y.lo, log_y), b = to_world(y.hi, log_y);
  return bottom - (to_world(y_data, log_y) - a) / (b - a) * (bottom - top);
}

Panel& Figure::add_panel(std::string y_label, std::string title) {
  Panel p;
  p.y_label = std::move(y_label);
  p.title = std::move(title);
  panels.push_back(std::move(p));
  return panels.back();
}

PanelGeometry Figure::geometry(std::size_t panel, int width_px, int height_px) const {
  if (panel >= panels.size())
    throw Error("figure geometry: panel " + std::to_string(panel) + " of " + std::to_string(panels.size()));
  return layout(*this, width_px, height_px)[panel];
}

void Figure::write_png(const std::string& path, int width_px, int height_px) const {
  if (panels.empty()) throw Error(path + ": the figure has no panels; nothing to draw");
  if (width_px < kMinPx || height_px < kMinPx || width_px > kMaxPx || height_px > kMaxPx) {
    throw Error(path + ": image size " + std::to_string(width_px) + "x" + std::to_string(height_px) +
                " px is outside " + std::to_string(kMinPx) + ".." + std::to_string(kMaxPx) + " px");
  }
  const std::vector<PanelGeometry> geometry = layout(*this, width_px, height_px);
  // given ranges must be drawable: finite, increasing, positive on log axes
  auto drawable = [](const Range& r, bool log) {
    return std::isfinite(r.lo) && std::isfinite(r.hi) && r.lo < r.hi && (!log || r.lo > 0.0);
  };
  for (std::size_t i = 0; i < geometry.size(); ++i) {
    if (!drawable(geometry[i].x, log_x) || !drawable(geometry[i].y, panels[i].log_y)) {
      throw Error(path + ": panel " + std::to_string(i) + " ('" + panels[i].y_label +
                  "') has an empty, reversed or non-positive log axis range");
    }
  }
  const std::vector<Rgb> colours = palette(*this);
  const std::string tmp = temporary_name(path);

  std::lock_guard<std::mutex> lock(plplot_mutex());
  if (!have_pngcairo()) {
    throw Error(path + ": PLplot has no pngcairo driver; install plplot-driver-cairo (scripts/common.sh)");
  }
  // we open the file so that a folder we cannot write into is our error, not a PLplot exit;
  // PLplot takes the FILE over and closes it when the stream ends
  FILE* file = std::fopen(tmp.c_str(), "wb");
  if (!file) {
    throw Error(path + ": cannot write the figure (" + std::strerror(errno) +
                "); check the folder exists and is writable");
  }
  RemoveOnExit cleanup(tmp);
  {
    // our own stream, ended (plend1) by its destructor, which also writes the PNG
    plstream pls;
    pls.sfile(file);
    pls.sdev("pngcairo");
    pls.spage(0.0, 0.0, width_px, height_px, 0, 0);
    pls.scmap0n(kFirstColour + static_cast<PLINT>(colours.size()));
    pls.scol0(kBackground, 255, 255, 255);
    pls.scol0(kInk, 0, 0, 0);
    pls.scol0(kShade, kShadeGrey.r, kShadeGrey.g, kShadeGrey.b);
    for (std::size_t i = 0; i < colours.size(); ++i)
      pls.scol0(kFirstColour + static_cast<PLINT>(i), colours[i].r, colours[i].g, colours[i].b);
    pls.init();
    pls.adv(0);
    // the text height in pixels: PLplot sizes text in mm of its page (known once a page is open)
    PLFLT x0_mm = 0.0, x1_mm = 0.0, y0_mm = 0.0, y1_mm = 0.0;
    pls.gspa(x0_mm, x1_mm, y0_mm, y1_mm);
    if (!(x1_mm > x0_mm)) throw Error(path + ": PLplot reports an empty page; cannot size the text");
    pls.schr(kTextPx * (x1_mm - x0_mm) / width_px, 1.0);
    for (std::size_t i = 0; i < panels.size(); ++i)
      draw_panel(pls, *this, i, geometry[i], width_px, height_px, colours);
    draw_legend(pls, *this, geometry.front(), width_px, height_px, colours);
  }
  if (!looks_like_png(tmp)) {
    throw Error(path + ": PLplot wrote no PNG (disk full?); the previous figure, if any, is untouched");
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) throw Error(path + ": cannot move the finished figure into place (" + ec.message() + ")");
  cleanup.release();
}

// ---- sim-to-real figures ------------------------------------------------------------------------

namespace {

// simulated runs cycle through these (Tableau 10: distinct, readable on white and on grey)
constexpr std::array<Rgb, 8> kRunColours = {{{31, 119, 180},
                                             {214, 39, 40},
                                             {44, 160, 44},
                                             {255, 127, 14},
                                             {148, 103, 189},
                                             {140, 86, 75},
                                             {227, 119, 194},
                                             {23, 190, 207}}};
constexpr Rgb kBlack{0, 0, 0};
// the pile: sand fill, darker outline
constexpr Rgb kPileFill{236, 222, 190};
constexpr Rgb kPileOutline{150, 120, 70};

constexpr double kN_per_kN = 1e3;
constexpr double kW_per_kW = 1e3;

Rgb run_colour(std::size_t i) { return kRunColours[i % kRunColours.size()]; }

std::string reference_label(const Run& r) { return r.label() + " (reference)"; }

std::vector<double> scaled(const std::vector<double>& v, double factor) {
  std::vector<double> out(v.size());
  std::transform(v.begin(), v.end(), out.begin(), [&](double x) { return x * factor; });
  return out;
}

// the grey intervals outside [dig_start, dig_end] over the time span [t0, t1]
// the model family of a fidelity label: its leading letters ("D" of "D50", "G" of "G200")
std::string family_of(const std::string& fidelity) {
  std::size_t n = 0;
  while (n < fidelity.size() && std::isalpha(static_cast<unsigned char>(fidelity[n]))) ++n;
  return fidelity.substr(0, n);
}

// the position of `name` in `names`, appended when new
std::size_t index_of(std::vector<std::string>& names, const std::string& name) {
  auto it = std::find(names.begin(), names.end(), name);
  if (it != names.end()) return static_cast<std::size_t>(it - names.begin());
  names.push_back(name);
  return names.size() - 1;
}

std::vector<Range> non_digging(const sim2real::RunSummary& s, double t0, double t1) {
  if (!s.dig_start_s || !s.dig_end_s) return {};
  std::vector<Range> out;
  if (*s.dig_start_s > t0) out.push_back({t0, *s.dig_start_s});
  if (*s.dig_end_s < t1) out.push_back({*s.dig_end_s, t1});
  return out;
}

Extent time_extent(const std::vector<const Run*>& runs) {
  Extent e;
  for (const Run* r : runs)
    if (r->series.size() > 0) {
      e.add(r->series[Channel::t].front());
      e.add(r->series[Channel::t].back());
    }
  return e;
}

// the reference first (when given), then the simulated runs
std::vector<const Run*> all_runs(const std::vector<Run>& simulated, const Run* reference) {
  std::vector<const Run*> out;
  if (reference) out.push_back(reference);
  for (const Run& r : simulated) out.push_back(&r);
  return out;
}

}  // namespace

Figure channel_figure(const std::vector<Run>& simulated, const Run* reference) {
  // each panel: channel, y label, factor from SI to the plotted unit
  struct ChannelPanel {
    Channel channel;
    const char* label;
    double factor;
  };
  const std::array<ChannelPanel, 7> kPanels = {{{Channel::v_drive, "drive speed [m/s]", 1.0},
                                                {Channel::f_traction, "traction force [kN]", 1.0 / kN_per_kN},
                                                {Channel::f_lift, "lift force [kN]", 1.0 / kN_per_kN},
                                                {Channel::f_tilt, "tilt force [kN]", 1.0 / kN_per_kN},
                                                {Channel::bucket_deg, "bucket angle [deg]", 1.0},
                                                {Channel::d_lift, "lift extension [m]", 1.0},
                                                {Channel::d_tilt, "tilt extension [m]", 1.0}}};
  Figure f;
  f.x_label = "time [s]";
  // the phase marks: the reference's, else the first simulated run's that has them
  const sim2real::RunSummary* marks = nullptr;
  if (reference && reference->summary.dig_start_s && reference->summary.dig_end_s) {
    marks = &reference->summary;
  }
  for (const Run& r : simulated)
    if (!marks && r.summary.dig_start_s && r.summary.dig_end_s) marks = &r.summary;
  const Extent span = time_extent(all_runs(simulated, reference));

  for (const ChannelPanel& cp : kPanels) {
    Panel& p = f.add_panel(cp.label);
    if (marks && !span.empty()) p.shaded = non_digging(*marks, span.lo, span.hi);
    for (std::size_t i = 0; i < simulated.size(); ++i) {
      const TimeSeries& s = simulated[i].series;
      p.series.push_back({s[Channel::t], scaled(s[cp.channel], cp.factor), run_colour(i), LineStyle::solid,
                          false, simulated[i].label()});
    }
    // the reference last, so its dashes stay visible over the simulated lines
    if (reference) {
      const TimeSeries& s = reference->series;
      p.series.push_back({s[Channel::t], scaled(s[cp.channel], cp.factor), kBlack, LineStyle::dashed, false,
                          reference_label(*reference)});
    }
  }
  return f;
}

Figure trajectory_figure(const std::vector<Run>& simulated, const Run* reference,
                         const std::vector<std::pair<double, double>>& pile_profile) {
  Figure f;
  f.x_label = "x [m]";
  Panel& p = f.add_panel("z [m]", "bucket-tip trajectory");
  p.equal_aspect = true;
  if (pile_profile.size() >= 2) {
    // the cross-section as a polygon closed along the ground z = 0
    Area pile{{}, {}, kPileFill, kPileOutline};
    pile.x.push_back(pile_profile.front().first);
    pile.y.push_back(0.0);
    for (const auto& [x, z] : pile_profile) {
      pile.x.push_back(x);
      pile.y.push_back(z);
    }
    pile.x.push_back(pile_profile.back().first);
    pile.y.push_back(0.0);
    p.areas.push_back(std::move(pile));
  }
  for (std::size_t i = 0; i < simulated.size(); ++i) {
    const TimeSeries& s = simulated[i].series;
    p.series.push_back({s[Channel::bucket_tip_x], s[Channel::bucket_tip_z], run_colour(i), LineStyle::solid,
                        false, simulated[i].label()});
  }
  if (reference) {
    const TimeSeries& s = reference->series;
    p.series.push_back({s[Channel::bucket_tip_x], s[Channel::bucket_tip_z], kBlack, LineStyle::dashed, false,
                        reference_label(*reference)});
  }
  return f;
}

std::vector<double> central_difference(const std::vector<double>& t, const std::vector<double>& f) {
  const std::size_t n = t.size();
  if (n < 2 || f.size() != n) {
    throw Error("central_difference: needs at least two samples and as many values as times (got " +
                std::to_string(n) + " times, " + std::to_string(f.size()) + " values)");
  }
  std::vector<double> d(n);
  d[0] = (f[1] - f[0]) / (t[1] - t[0]);
  d[n - 1] = (f[n - 1] - f[n - 2]) / (t[n - 1] - t[n - 2]);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    // second-order on uneven spacing: the weighted mean of the two one-sided slopes
    double h0 = t[i] - t[i - 1], h1 = t[i + 1] - t[i];
    double s0 = (f[i] - f[i - 1]) / h0, s1 = (f[i + 1] - f[i]) / h1;
    d[i] = (h1 * s0 + h0 * s1) / (h0 + h1);
  }
  return d;
}

PowerSplit power_split(const TimeSeries& s) {
  PowerSplit p;
  const std::size_t n = s.size();
  p.t = s[Channel::t];
  p.drive.resize(n);
  p.lift.resize(n);
  p.tilt.resize(n);
  p.total.resize(n);
  if (n < 2) return p;
  const std::vector<double> v_lift = central_difference(s[Channel::t], s[Channel::d_lift]);
  const std::vector<double> v_tilt = central_difference(s[Channel::t], s[Channel::d_tilt]);
  for (std::size_t i = 0; i < n; ++i) {
    p.drive[i] = s[Channel::f_traction][i] * s[Channel::v_drive][i];
    p.lift[i] = s[Channel::f_lift][i] * v_lift[i];
    p.tilt[i] = s[Channel::f_tilt][i] * v_tilt[i];
    p.total[i] = p.drive[i] + p.lift[i] + p.tilt[i];
  }
  return p;
}

Figure power_figure(const std::vector<Run>& simulated, const Run* reference) {
  Figure f;
  f.x_label = "time [s]";
  const Extent span = time_extent(all_runs(simulated, reference));
  for (const Run* r : all_runs(simulated, reference)) {
    const bool is_reference = r == reference;
    Panel& p = f.add_panel("power [kW]", is_reference ? reference_label(*r) : r->label());
    if (!span.empty()) p.shaded = non_digging(r->summary, span.lo, span.hi);
    const PowerSplit ps = power_split(r->series);
    // one colour per consumer across all panels, so the legend holds four entries; the total
    // dashed on top, so a consumer it coincides with still shows through its gaps
    const double kw = 1.0 / kW_per_kW;
    p.series.push_back({ps.t, scaled(ps.drive, kw), kRunColours[0], LineStyle::solid, false, "drive"});
    p.series.push_back({ps.t, scaled(ps.lift, kw), kRunColours[1], LineStyle::solid, false, "lift"});
    p.series.push_back({ps.t, scaled(ps.tilt, kw), kRunColours[2], LineStyle::solid, false, "tilt"});
    p.series.push_back({ps.t, scaled(ps.total, kw), kBlack, LineStyle::dashed, false, "total"});
  }
  return f;
}

Figure resolution_figure(const std::vector<ResolutionPoint>& points) {
  Figure f;
  f.x_label = "particle diameter D [mm]";
  f.log_x = true;
  f.add_panel("mean error [-]");
  f.add_panel("real-time factor [-]");
  Panel& error = f.panels[0];
  Panel& speed = f.panels[1];
  speed.log_y = true;
  // the lines: one per (scenario, family); colour by scenario, line style by family
  std::vector<std::string> scenarios, families;
  std::map<std::pair<std::string, std::string>, std::vector<const ResolutionPoint*>> lines;
  for (const ResolutionPoint& pt : points) {
    const std::string family = family_of(pt.fidelity);
    index_of(scenarios, pt.scenario);
    index_of(families, family);
    lines[{pt.scenario, family}].push_back(&pt);
  }
  for (auto& [key, pts] : lines) {
    std::sort(pts.begin(), pts.end(),
              [](const ResolutionPoint* a, const ResolutionPoint* b) { return a->d_mm < b->d_mm; });
    const Rgb colour = run_colour(index_of(scenarios, key.first));
    const LineStyle style = index_of(families, key.second) % 2 == 0 ? LineStyle::solid : LineStyle::dashed;
    const std::string label = key.second.empty() ? key.first : key.first + " " + key.second;
    Series e{{}, {}, colour, style, true, label}, r{{}, {}, colour, style, true, label};
    for (const ResolutionPoint* pt : pts) {
      e.x.push_back(pt->d_mm);
      e.y.push_back(pt->mean_error);
      r.x.push_back(pt->d_mm);
      r.y.push_back(pt->realtime_factor);
    }
    error.series.push_back(std::move(e));
    speed.series.push_back(std::move(r));
  }
  return f;
}

Figure throughput_figure(const std::vector<ThroughputPoint>& points) {
  Figure f;
  f.x_label = "particle diameter D [mm]";
  f.log_x = true;
  f.add_panel("contact updates per second [million/s]", "DEM throughput (talus bench dem)");
  f.add_panel("real-time factor [-]");
  Panel& updates = f.panels[0];
  Panel& speed = f.panels[1];
  updates.log_y = true;
  speed.log_y = true;
  // the devices in order of first appearance, each device's levels in order of size
  std::vector<std::string> devices;
  for (const ThroughputPoint& pt : points)
    if (std::find(devices.begin(), devices.end(), pt.device) == devices.end())
      devices.push_back(pt.device);
  std::vector<const ThroughputPoint*> sorted;
  sorted.reserve(points.size());
  for (const ThroughputPoint& pt : points) sorted.push_back(&pt);
  std::sort(sorted.begin(), sorted.end(),
            [](const ThroughputPoint* a, const ThroughputPoint* b) { return a->d_mm < b->d_mm; });
  // one marked line per device and measure, one colour per device
  std::vector<Series> u_lines, r_lines;
  std::vector<double> all_u, all_r;
  for (size_t k = 0; k < devices.size(); ++k) {
    const std::string label = devices[k].empty() ? "talus" : devices[k];
    Series u{{}, {}, run_colour(k), LineStyle::solid, true, devices.size() > 1 ? label : ""};
    Series r{{}, {}, run_colour(k), LineStyle::solid, true, label};
    for (const ThroughputPoint* pt : sorted) {
      if (pt->device != devices[k]) continue;
      u.x.push_back(pt->d_mm);
      u.y.push_back(1e-6 * pt->contact_updates_per_s);
      r.x.push_back(pt->d_mm);
      r.y.push_back(pt->realtime_factor);
    }
    all_u.insert(all_u.end(), u.y.begin(), u.y.end());
    all_r.insert(all_r.end(), r.y.begin(), r.y.end());
    u_lines.push_back(std::move(u));
    r_lines.push_back(std::move(r));
  }
  // real time, for reference, across the measured sizes
  if (!sorted.empty()) {
    Series one{{sorted.front()->d_mm, sorted.back()->d_mm},
               {1.0, 1.0},
               Rgb{0, 0, 0},
               LineStyle::dashed,
               false,
               "real time"};
    speed.series.push_back(std::move(one));
  }
  // whole decades on the y axes, at least kFewDecades of them, so the axes are labelled at
  // decades (a shorter log axis would be labelled at doublings of the smallest value: 10.37, 20.75)
  auto decades = [](const std::vector<double>& y) -> std::optional<Range> {
    double lo = 0.0, hi = 0.0;
    for (double v : y)
      if (finite_positive(v)) {
        lo = lo > 0.0 ? std::min(lo, v) : v;
        hi = std::max(hi, v);
      }
    if (!(lo > 0.0)) return std::nullopt;
    const double top = std::ceil(std::log10(hi) + 1e-9);
    const double bottom = std::min(std::floor(std::log10(lo)), top - kFewDecades);
    return Range{std::pow(10.0, bottom), std::pow(10.0, top)};
  };
  updates.y_range = decades(all_u);
  all_r.push_back(1.0);
  speed.y_range = decades(all_r);
  for (Series& line : u_lines) updates.series.push_back(std::move(line));
  for (Series& line : r_lines) speed.series.push_back(std::move(line));
  return f;
}

Rgb series_colour(std::size_t i) { return run_colour(i); }

}  // namespace talus
