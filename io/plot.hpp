// Paper-style figures as PNG through PLplot (pngcairo): a Figure is one or more panels stacked
// vertically over a shared x axis, each with its y label, series, grey shaded x-intervals and
// filled areas; builders make the figures of the sim-to-real comparison from recorded runs
// (docs/plots.md). Figures are plain data; only write_png touches PLplot.
#pragma once
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sim2real/timeseries.hpp"

namespace talus {

// an 8-bit sRGB colour
struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};
inline bool operator==(const Rgb& a, const Rgb& b) { return a.r == b.r && a.g == b.g && a.b == b.b; }

// the grey of shaded x-intervals (paper: phases outside the digging phase)
inline constexpr Rgb kShadeGrey{210, 210, 210};

enum class LineStyle { solid, dashed };

// an interval [lo, hi] on an axis, in data units
struct Range {
  double lo = 0.0, hi = 0.0;
};

// one curve: points (x[i], y[i]) joined by a line; non-finite points break the line
struct Series {
  std::vector<double> x, y;
  Rgb colour;
  LineStyle style = LineStyle::solid;
  bool markers = false;  // a dot on every point (sparse data, e.g. resolution sweeps)
  std::string label;     // legend entry; empty keeps it out of the legend
};

// a filled polygon drawn under the series (e.g. the pile's cross-section)
struct Area {
  std::vector<double> x, y;
  Rgb fill;
  Rgb outline;
};

struct Panel {
  std::string y_label;              // with its unit, e.g. "lift force [kN]"
  std::string title;                // optional, above the panel
  std::vector<Series> series;
  std::vector<Range> shaded;        // grey x-intervals behind the data
  std::vector<Area> areas;
  bool log_y = false;
  // one data unit is as long across as up (bucket-tip paths over a pile): the shorter data
  // range is widened to fill the panel, the panel's box itself keeps its place
  bool equal_aspect = false;
  std::optional<Range> y_range;     // default: the data's extent plus a margin
};

// where a panel lands in the image: its plot box in pixels (origin top-left, x right, y down)
// and the data ranges the box spans
struct PanelGeometry {
  double left = 0.0, right = 0.0, top = 0.0, bottom = 0.0;  // [px]
  Range x, y;                                               // data units
  bool log_x = false, log_y = false;

  double column(double x_data) const;  // pixel column of a data x
  double row(double y_data) const;     // pixel row of a data y
};

struct Figure {
  std::string x_label;              // under the bottom panel, with its unit
  bool log_x = false;
  std::optional<Range> x_range;     // default: the data's extent (series and areas)
  std::vector<Panel> panels;        // top to bottom

  Panel& add_panel(std::string y_label, std::string title = {});

  // the layout write_png draws for an image of width_px x height_px
  PanelGeometry geometry(std::size_t panel, int width_px, int height_px) const;

  // draws with PLplot's pngcairo driver into a temporary file next to `path`, then renames it
  // into place; talus::Error naming `path` when the folder is not writable, the driver is
  // missing or the figure is empty (no temporary file is left behind)
  void write_png(const std::string& path, int width_px, int height_px) const;
};

// a panel's y label as drawn: one line, or, when "name [unit]" is longer than the panel is high,
// the name and the unit on two lines (the unit nearer the axis); `scale` (0.7 to 1) shrinks the
// text further when a line is still too long. The length is estimated from the character count
// (io/plot.cpp: kCharWidthEm)
struct YLabelLines {
  std::vector<std::string> lines;
  double scale = 1.0;
};
YLabelLines y_label_lines(const std::string& label, double panel_px);

// ---- figures of the sim-to-real comparison --------------------------------------------------

// the size of the run figures talus writes (channels, trajectory, power; talus run and talus
// diagnose) [px]: a 1.4:1 page that holds the channel grid legibly
inline constexpr int kFigureWidth = 1400, kFigureHeight = 1000;

// channel overlays against time: drive speed, traction, lift and tilt force [kN], bucket angle,
// lift and tilt extension; the reference (measured) run dashed black, simulated runs coloured;
// the phases outside digging shaded grey when the reference (else the first simulated run
// that has them) carries dig_start_s and dig_end_s. `reference` may be null.
Figure channel_figure(const std::vector<sim2real::Run>& simulated, const sim2real::Run* reference);

// bucket-tip paths (bucket_tip_x, bucket_tip_z) at equal aspect over the pile's cross-section,
// a polyline of (x, z) points [m] (may be empty)
Figure trajectory_figure(const std::vector<sim2real::Run>& simulated, const sim2real::Run* reference,
                         const std::vector<std::pair<double, double>>& pile_profile);

// the power the machine delivers, split by consumer [W]: drive f_traction * v_drive, lift
// f_lift * d(d_lift)/dt, tilt f_tilt * d(d_tilt)/dt, and their sum
struct PowerSplit {
  std::vector<double> t, drive, lift, tilt, total;
};
PowerSplit power_split(const sim2real::TimeSeries& series);

// df/dt by central differences on a possibly uneven time base (one-sided at the ends);
// t strictly increasing, at least two samples
std::vector<double> central_difference(const std::vector<double>& t, const std::vector<double>& f);

// one panel per run (the reference first when given), each with its power split in kW
Figure power_figure(const std::vector<sim2real::Run>& simulated, const sim2real::Run* reference);

// one simulated case of a resolution sweep
struct ResolutionPoint {
  std::string scenario;          // e.g. "FB35"
  std::string fidelity;          // e.g. "D50", "G200": its leading letters name the model family
  double d_mm = 0.0;             // particle diameter D [mm]
  double mean_error = 0.0;       // the error table's mean column [-]
  double realtime_factor = 0.0;  // simulated time over wall time [-]
};

// mean error (top) and real-time factor (bottom, log) against D (log), one line per scenario
// and model family: colour by scenario, solid for the first family, dashed for the next
Figure resolution_figure(const std::vector<ResolutionPoint>& points);

// one level of the DEM throughput benchmark (talus bench dem) on one device
struct ThroughputPoint {
  std::string level;                   // e.g. "D200"
  double d_mm = 0.0;                   // particle diameter D [mm]
  double contact_updates_per_s = 0.0;  // contacts x sweeps per second of sweeping [1/s]
  double realtime_factor = 0.0;        // simulated time over wall time of whole steps [-]
  std::string device;                  // the legend's name of the device measured on ("" alone)
};

// contact updates per second (top, log, in millions) and real-time factor (bottom, log) against D
// (log), one marked line per device in the order the devices first appear, the real-time line
// with the factor 1 dashed for reference
Figure throughput_figure(const std::vector<ThroughputPoint>& points);

// the colour of the i-th simulated series in every figure (a cycle of eight distinct hues)
Rgb series_colour(std::size_t i);

}  // namespace talus
