// io/plot: figures written through PLplot are read back with libpng and checked where the
// layout says things land: size, line colours, dashes, grey shading, failure paths; plus the
// power split's numerics and `talus plot` end to end.
#include <gtest/gtest.h>
#include <png.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "host/error.hpp"
#include "host/files.hpp"
#include "io/plot.hpp"
#include "sim2real/timeseries.hpp"

namespace talus {
namespace {

namespace fs = std::filesystem;
using sim2real::Channel;

// an RGB image read back with libpng's simplified API
struct Pixels {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  const std::uint8_t* at(int x, int y) const { return &rgb[3 * (std::size_t(y) * width + x)]; }
};

Pixels read_png(const std::string& path) {
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str())) {
    ADD_FAILURE() << path << ": " << image.message;
    return {};
  }
  image.format = PNG_FORMAT_RGB;
  Pixels p;
  p.width = static_cast<int>(image.width);
  p.height = static_cast<int>(image.height);
  p.rgb.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, p.rgb.data(), 0, nullptr)) {
    ADD_FAILURE() << path << ": " << image.message;
    return {};
  }
  return p;
}

// within `tol` of `c` in every channel (anti-aliased edges blend into the background)
bool near(const std::uint8_t* px, const Rgb& c, int tol) {
  return std::abs(px[0] - c.r) <= tol && std::abs(px[1] - c.g) <= tol && std::abs(px[2] - c.b) <= tol;
}

// a fresh folder per test, removed afterwards
class PlotTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("talus_plot_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

constexpr Rgb kRed{220, 20, 20};
constexpr Rgb kBlue{20, 40, 220};
constexpr int kW = 800, kH = 600;

// one panel on [0, 10] x [0, 1] with the given series
Figure unit_figure() {
  Figure f;
  f.x_label = "time [s]";
  f.x_range = Range{0.0, 10.0};
  Panel& p = f.add_panel("value [-]");
  p.y_range = Range{0.0, 1.0};
  return f;
}

Series horizontal(double y, Rgb colour, LineStyle style, const std::string& label = {}) {
  return {{0.0, 10.0}, {y, y}, colour, style, false, label};
}

// the fraction of columns between data x0 and x1 with a pixel of `colour` within two rows
// of the data height y
double coverage(const Pixels& img, const PanelGeometry& g, double x0, double x1, double y, const Rgb& colour) {
  const int c0 = static_cast<int>(std::ceil(g.column(x0))), c1 = static_cast<int>(std::floor(g.column(x1)));
  const int r = static_cast<int>(std::lround(g.row(y)));
  int hit = 0;
  for (int c = c0; c <= c1; ++c) {
    bool any = false;
    for (int dr = -2; dr <= 2; ++dr) any = any || near(img.at(c, r + dr), colour, 40);
    hit += any;
  }
  return double(hit) / double(c1 - c0 + 1);
}

TEST_F(PlotTest, PngHasTheRequestedPixelSize) {
  Figure f = unit_figure();
  f.panels[0].series.push_back(horizontal(0.5, kRed, LineStyle::solid, "a"));
  f.write_png(file("size.png"), 640, 430);
  ASSERT_TRUE(fs::exists(file("size.png")));
  Pixels img = read_png(file("size.png"));
  EXPECT_EQ(img.width, 640);
  EXPECT_EQ(img.height, 430);
  EXPECT_FALSE(fs::exists(temporary_name(file("size.png"))));
  // text is drawn: the y tick labels and y label leave dark pixels left of the plot box
  const PanelGeometry g = f.geometry(0, 640, 430);
  int dark = 0;
  for (int r = static_cast<int>(g.top); r < static_cast<int>(g.bottom); ++r)
    for (int c = 0; c < static_cast<int>(g.left) - 6; ++c) dark += near(img.at(c, r), Rgb{0, 0, 0}, 80);
  EXPECT_GT(dark, 200);
}

TEST_F(PlotTest, SolidAndDashedSeriesLeaveTheirColourWhereTheLayoutPutsThem) {
  Figure f = unit_figure();
  f.panels[0].series.push_back(horizontal(0.25, kRed, LineStyle::solid, "solid"));
  f.panels[0].series.push_back(horizontal(0.75, kBlue, LineStyle::dashed, "dashed"));
  f.write_png(file("lines.png"), kW, kH);
  Pixels img = read_png(file("lines.png"));
  ASSERT_EQ(img.width, kW);
  const PanelGeometry g = f.geometry(0, kW, kH);
  // the solid line covers its row; the dashed one leaves gaps but is clearly there
  EXPECT_GT(coverage(img, g, 0.5, 9.5, 0.25, kRed), 0.97);
  const double dashed = coverage(img, g, 0.5, 9.5, 0.75, kBlue);
  EXPECT_GT(dashed, 0.25);
  EXPECT_LT(dashed, 0.85);
  // and neither colour where the other line is
  EXPECT_EQ(coverage(img, g, 0.5, 9.5, 0.75, kRed), 0.0);
  EXPECT_EQ(coverage(img, g, 0.5, 9.5, 0.25, kBlue), 0.0);
}

TEST_F(PlotTest, ShadedIntervalIsGreyInsideAndWhiteOutside) {
  Figure f = unit_figure();
  f.panels[0].shaded.push_back({2.0, 4.0});
  f.panels[0].series.push_back(horizontal(0.9, kRed, LineStyle::solid));
  f.write_png(file("shade.png"), kW, kH);
  Pixels img = read_png(file("shade.png"));
  ASSERT_EQ(img.width, kW);
  const PanelGeometry g = f.geometry(0, kW, kH);
  // rows well away from the series and the box edges; columns 3 px clear of the interval's
  // edges (anti-aliasing) and of the box
  constexpr int kClear = 3;
  const int r0 = static_cast<int>(g.row(0.7)), r1 = static_cast<int>(g.row(0.1));
  auto count_grey = [&](double x0, double x1) {
    int grey = 0, total = 0;
    for (int r = r0; r <= r1; r += 5)
      for (int c = static_cast<int>(g.column(x0)) + kClear; c <= static_cast<int>(g.column(x1)) - kClear; ++c) {
        grey += near(img.at(c, r), kShadeGrey, 6);
        ++total;
      }
    return std::pair<int, int>{grey, total};
  };
  auto [inside, inside_total] = count_grey(2.0, 4.0);
  EXPECT_GT(inside_total, 100);
  EXPECT_EQ(inside, inside_total);
  // left of and right of the interval: no grey (tick marks sit on the box edges, not here)
  auto [left, left_total] = count_grey(0.2, 2.0);
  auto [right, right_total] = count_grey(4.0, 9.8);
  EXPECT_GT(left_total + right_total, 100);
  EXPECT_EQ(left + right, 0);
}

TEST_F(PlotTest, UnwritableFolderThrowsNamingThePathAndLeavesNoTemporary) {
  Figure f = unit_figure();
  f.panels[0].series.push_back(horizontal(0.5, kRed, LineStyle::solid));
  const std::string missing = file("no/such/folder/fig.png");
  try {
    f.write_png(missing, kW, kH);
    FAIL() << "expected talus::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  // the rename fails when the target is a non-empty folder: the finished temporary goes away
  fs::create_directories(file("taken.png/inside"));
  try {
    f.write_png(file("taken.png"), kW, kH);
    FAIL() << "expected talus::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(file("taken.png")), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(temporary_name(file("taken.png"))));
  for (const auto& entry : fs::directory_iterator(dir_))
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
}

TEST_F(PlotTest, TwoFiguresInARowBothSucceed) {
  Figure a = unit_figure();
  a.panels[0].series.push_back(horizontal(0.25, kRed, LineStyle::solid, "red"));
  Figure b = unit_figure();
  b.add_panel("second [-]").series.push_back(horizontal(0.5, kBlue, LineStyle::dashed, "blue"));
  a.write_png(file("a.png"), kW, kH);
  b.write_png(file("b.png"), 500, 700);
  a.write_png(file("c.png"), kW, kH);
  Pixels pa = read_png(file("a.png")), pb = read_png(file("b.png")), pc = read_png(file("c.png"));
  EXPECT_EQ(pa.width, kW);
  EXPECT_EQ(pb.width, 500);
  EXPECT_EQ(pb.height, 700);
  // the same figure drawn again is the same picture: no state leaks from one stream to the next
  EXPECT_EQ(pa.rgb, pc.rgb);
  // the second figure's blue line is in its second panel
  const PanelGeometry g = b.geometry(1, 500, 700);
  EXPECT_GT(coverage(pb, g, 0.5, 9.5, 0.5, kBlue), 0.25);
}

TEST_F(PlotTest, EmptyFigureAndAbsurdSizesAreErrors) {
  EXPECT_THROW(Figure().write_png(file("empty.png"), kW, kH), Error);
  EXPECT_THROW(unit_figure().write_png(file("tiny.png"), 10, 10), Error);
  Figure reversed = unit_figure();
  reversed.x_range = Range{10.0, 0.0};
  EXPECT_THROW(reversed.write_png(file("reversed.png"), kW, kH), Error);
  Figure log_from_zero = unit_figure();
  log_from_zero.panels[0].log_y = true;  // y_range starts at 0
  EXPECT_THROW(log_from_zero.write_png(file("log.png"), kW, kH), Error);
  EXPECT_FALSE(fs::exists(file("empty.png")));
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST(PlotLayout, StackedPanelsShareXAndDoNotOverlap) {
  Figure f;
  f.add_panel("a").series.push_back({{1.0, 3.0}, {0.0, 1.0}, kRed, LineStyle::solid, false, ""});
  f.add_panel("b").series.push_back({{2.0, 5.0}, {0.0, 1.0}, kRed, LineStyle::solid, false, ""});
  const PanelGeometry a = f.geometry(0, kW, kH), b = f.geometry(1, kW, kH);
  EXPECT_DOUBLE_EQ(a.x.lo, 1.0);  // time axes are tight: the union of the data
  EXPECT_DOUBLE_EQ(a.x.hi, 5.0);
  EXPECT_DOUBLE_EQ(b.x.lo, a.x.lo);
  EXPECT_DOUBLE_EQ(a.left, b.left);
  EXPECT_LT(a.bottom, b.top);
  EXPECT_GT(a.top, 0.0);
  EXPECT_LT(b.bottom, kH);
}

TEST(PlotLayout, EqualAspectPanelHasEqualPixelsPerMetre) {
  Figure f;
  Panel& p = f.add_panel("z [m]");
  p.equal_aspect = true;
  p.series.push_back({{0.0, 6.0}, {0.0, 0.5}, kRed, LineStyle::solid, false, ""});  // wide and flat
  for (auto [w, h] : {std::pair<int, int>{1200, 700}, {400, 900}}) {
    const PanelGeometry g = f.geometry(0, w, h);
    const double across = (g.right - g.left) / (g.x.hi - g.x.lo);
    const double up = (g.bottom - g.top) / (g.y.hi - g.y.lo);
    EXPECT_NEAR(across / up, 1.0, 1e-9) << w << "x" << h;
    EXPECT_LE(g.x.lo, 0.0);  // the data still fits
    EXPECT_GE(g.x.hi, 6.0);
    EXPECT_LE(g.y.lo, 0.0);
    EXPECT_GE(g.y.hi, 0.5);
  }
}

TEST(PlotLayout, LogAxesMapDecadesEvenly) {
  Figure f;
  f.log_x = true;
  f.x_range = Range{10.0, 1000.0};
  Panel& p = f.add_panel("rtf [-]");
  p.log_y = true;
  p.y_range = Range{0.01, 100.0};
  const PanelGeometry g = f.geometry(0, kW, kH);
  EXPECT_NEAR(g.column(100.0), 0.5 * (g.left + g.right), 1e-9);
  EXPECT_NEAR(g.row(1.0), 0.5 * (g.top + g.bottom), 1e-9);
}

TEST(PowerSplit, CentralDifferencesAreExactForQuadraticsOnUnevenTimes) {
  const std::vector<double> t = {0.0, 0.1, 0.25, 0.3, 0.5, 0.8};
  std::vector<double> f(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) f[i] = 3.0 * t[i] * t[i] - 2.0 * t[i] + 1.0;
  const std::vector<double> d = central_difference(t, f);
  for (std::size_t i = 1; i + 1 < t.size(); ++i) EXPECT_NEAR(d[i], 6.0 * t[i] - 2.0, 1e-12) << i;
  // the ends are one-sided: the slope of the end segment
  EXPECT_NEAR(d.front(), (f[1] - f[0]) / (t[1] - t[0]), 1e-12);
  EXPECT_THROW(central_difference({0.0}, {1.0}), Error);
}

// a run of n samples at 100 Hz: extensions move at constant speed, forces constant
sim2real::Run synthetic_run(const std::string& name, double v_lift, double f_lift, double v_tilt, double f_tilt,
                            double traction, double speed) {
  constexpr std::size_t n = 200;
  constexpr double dt = 0.01;  // 100 Hz
  sim2real::Run r;
  r.dir = name;
  r.summary.scenario = "FB35";
  r.summary.fidelity = name;
  for (std::size_t i = 0; i < n; ++i) {
    double t = i * dt;
    r.series[Channel::t].push_back(t);
    r.series[Channel::f_lift].push_back(f_lift);
    r.series[Channel::f_tilt].push_back(f_tilt);
    r.series[Channel::f_traction].push_back(traction);
    r.series[Channel::v_drive].push_back(speed);
    r.series[Channel::d_lift].push_back(0.5 + v_lift * t);
    r.series[Channel::d_tilt].push_back(0.7 + v_tilt * t);
    r.series[Channel::boom_deg].push_back(-20.0 + t);
    r.series[Channel::bucket_deg].push_back(10.0 * t);
    r.series[Channel::pitch_deg].push_back(0.0);
    r.series[Channel::x_vehicle].push_back(8.0 - speed * t);
    r.series[Channel::bucket_tip_x].push_back(0.5 + speed * t);
    r.series[Channel::bucket_tip_z].push_back(0.1 + 0.3 * t * t);
    r.series[Channel::power].push_back(0.0);
  }
  return r;
}

TEST(PowerSplit, ForceTimesRate) {
  const sim2real::Run r = synthetic_run("D200", 0.05, 2.0e5, -0.02, 1.0e5, 3.0e4, 1.5);
  const PowerSplit p = power_split(r.series);
  ASSERT_EQ(p.t.size(), r.series.size());
  for (std::size_t i = 0; i < p.t.size(); ++i) {
    EXPECT_NEAR(p.drive[i], 3.0e4 * 1.5, 1e-6);
    EXPECT_NEAR(p.lift[i], 2.0e5 * 0.05, 1e-6);
    EXPECT_NEAR(p.tilt[i], 1.0e5 * -0.02, 1e-6);
    EXPECT_NEAR(p.total[i], p.drive[i] + p.lift[i] + p.tilt[i], 1e-9);
  }
}

TEST(PlotBuilders, ChannelFigureShadesOutsideDiggingAndDrawsTheReferenceDashedBlack) {
  sim2real::Run ref = synthetic_run("field", 0.05, 2.0e5, -0.02, 1.0e5, 3.0e4, 1.5);
  ref.summary.dig_start_s = 0.5;
  ref.summary.dig_end_s = 1.5;
  const std::vector<sim2real::Run> sims = {synthetic_run("D200", 0.04, 1.8e5, -0.02, 0.9e5, 2.5e4, 1.4),
                                           synthetic_run("D100", 0.05, 1.9e5, -0.02, 1.1e5, 2.8e4, 1.5)};
  const Figure f = channel_figure(sims, &ref);
  ASSERT_EQ(f.panels.size(), 7u);
  for (const Panel& p : f.panels) {
    ASSERT_EQ(p.shaded.size(), 2u);
    EXPECT_DOUBLE_EQ(p.shaded[0].lo, 0.0);
    EXPECT_DOUBLE_EQ(p.shaded[0].hi, 0.5);
    EXPECT_DOUBLE_EQ(p.shaded[1].lo, 1.5);
    EXPECT_NEAR(p.shaded[1].hi, 1.99, 1e-12);
    ASSERT_EQ(p.series.size(), 3u);
    EXPECT_EQ(p.series.back().style, LineStyle::dashed);
    EXPECT_EQ(p.series.back().colour, (Rgb{0, 0, 0}));
    EXPECT_FALSE(p.series[0].colour == p.series[1].colour);
  }
  // forces in kN
  EXPECT_NEAR(f.panels[2].series.back().y.front(), 200.0, 1e-9);
  // without phase marks nothing is shaded
  EXPECT_TRUE(channel_figure(sims, nullptr).panels[0].shaded.empty());
}

TEST_F(PlotTest, BuilderFiguresWrite) {
  sim2real::Run ref = synthetic_run("field", 0.05, 2.0e5, -0.02, 1.0e5, 3.0e4, 1.5);
  ref.summary.dig_start_s = 0.5;
  ref.summary.dig_end_s = 1.5;
  const std::vector<sim2real::Run> sims = {synthetic_run("D200", 0.04, 1.8e5, -0.02, 0.9e5, 2.5e4, 1.4)};
  channel_figure(sims, &ref).write_png(file("channels.png"), 1200, 1800);
  trajectory_figure(sims, &ref, {{0.0, 0.0}, {3.2, 2.0}, {5.1, 2.0}}).write_png(file("trajectory.png"), 1200, 700);
  power_figure(sims, &ref).write_png(file("power.png"), 1200, 750);
  const std::vector<ResolutionPoint> sweep = {{"FB35", "D50", 50, 0.20, 1e-4},  {"FB35", "D200", 200, 0.30, 0.05},
                                              {"FB35", "G200", 200, 0.25, 1.0}, {"FB35", "G50", 50, 0.22, 0.01},
                                              {"HD27", "D200", 200, 0.35, 0.04}, {"HD27", "D100", 100, 0.3, 0.005}};
  const Figure rf = resolution_figure(sweep);
  ASSERT_EQ(rf.panels.size(), 2u);
  EXPECT_EQ(rf.panels[0].series.size(), 3u);  // FB35 D, FB35 G, HD27 D
  EXPECT_TRUE(rf.log_x);
  EXPECT_TRUE(rf.panels[1].log_y);
  rf.write_png(file("resolution.png"), 1000, 800);
  for (const char* name : {"channels.png", "trajectory.png", "power.png", "resolution.png"}) {
    EXPECT_GT(read_png(file(name)).width, 0) << name;
  }
  // the trajectory's pile is drawn: sand-coloured pixels under the profile's flat top
  const Figure tf = trajectory_figure(sims, &ref, {{0.0, 0.0}, {3.2, 2.0}, {5.1, 2.0}});
  const PanelGeometry g = tf.geometry(0, 1200, 700);
  Pixels img = read_png(file("trajectory.png"));
  const std::uint8_t* px = img.at(static_cast<int>(g.column(4.5)), static_cast<int>(g.row(1.0)));
  EXPECT_TRUE(near(px, Rgb{236, 222, 190}, 6)) << int(px[0]) << "," << int(px[1]) << "," << int(px[2]);
}

TEST_F(PlotTest, ShortLogAxisIsLabelledAtEveryDoubling) {
  // 50..400 mm spans less than a decade: PLplot alone would label none of the points
  const std::vector<ResolutionPoint> sweep = {{"FB35", "D50", 50, 0.2, 1e-4}, {"FB35", "D100", 100, 0.25, 1e-3},
                                              {"FB35", "D200", 200, 0.3, 1e-2}, {"FB35", "D400", 400, 0.4, 1.0}};
  const Figure f = resolution_figure(sweep);
  constexpr int kFigW = 1000, kFigH = 800;
  f.write_png(file("sweep.png"), kFigW, kFigH);
  Pixels img = read_png(file("sweep.png"));
  ASSERT_EQ(img.width, kFigW);
  const PanelGeometry g = f.geometry(1, kFigW, kFigH);
  // dark pixels in the tick-label band under the bottom panel, within 20 px of a column
  auto ink_under = [&](double d_mm) {
    constexpr int kHalfWidth = 20, kBandTop = 4, kBandBottom = 30;  // [px] below the box
    const int c = static_cast<int>(g.column(d_mm)), r = static_cast<int>(g.bottom);
    int dark = 0;
    for (int y = r + kBandTop; y <= r + kBandBottom; ++y)
      for (int x = c - kHalfWidth; x <= c + kHalfWidth; ++x) dark += near(img.at(x, y), Rgb{0, 0, 0}, 80);
    return dark;
  };
  for (double d : {50.0, 100.0, 200.0, 400.0}) EXPECT_GT(ink_under(d), 10) << d << " mm";
  // and nothing between the labels
  EXPECT_EQ(ink_under(std::sqrt(100.0 * 200.0)), 0);
}

// the throughput figure: both panels logarithmic over a logarithmic D, the levels joined in order
// of size whatever order they were measured in, and real time drawn across the sizes for reference
TEST_F(PlotTest, ThroughputFigureDrawsTheLevelsInOrderOfSize) {
  const std::vector<ThroughputPoint> levels = {{"D200", 200, 3.1e7, 0.037, ""},
                                               {"D400", 400, 1.6e7, 4.6, ""},
                                               {"D100", 100, 3.2e7, 0.0054, ""}};
  const Figure f = throughput_figure(levels);
  ASSERT_EQ(f.panels.size(), 2u);
  EXPECT_TRUE(f.log_x);
  EXPECT_TRUE(f.panels[0].log_y);
  EXPECT_TRUE(f.panels[1].log_y);
  ASSERT_EQ(f.panels[0].series.size(), 1u);
  EXPECT_EQ(f.panels[0].series[0].x, (std::vector<double>{100, 200, 400}));
  EXPECT_EQ(f.panels[0].series[0].y, (std::vector<double>{32, 31, 16}));  // millions per second
  ASSERT_EQ(f.panels[1].series.size(), 2u);
  EXPECT_EQ(f.panels[1].series[0].y, (std::vector<double>{1.0, 1.0}));
  EXPECT_EQ(f.panels[1].series[1].y, (std::vector<double>{0.0054, 0.037, 4.6}));
  f.write_png(file("throughput.png"), 1000, 800);
  EXPECT_EQ(read_png(file("throughput.png")).width, 1000);
}

// two devices: one line each in both panels, in the order the devices first appear, each in its
// own colour and named in the legend; the axes span both devices' values
TEST_F(PlotTest, ThroughputFigureDrawsOneLinePerDevice) {
  const std::vector<ThroughputPoint> levels = {{"D400", 400, 1.1e7, 3.9, "EPYC"},
                                               {"D50", 50, 5.4e9, 0.042, "H100"},
                                               {"D200", 200, 2.7e7, 0.033, "EPYC"},
                                               {"D400", 400, 4.1e7, 15.1, "H100"}};
  const Figure f = throughput_figure(levels);
  ASSERT_EQ(f.panels[0].series.size(), 2u);
  EXPECT_EQ(f.panels[0].series[0].label, "EPYC");
  EXPECT_EQ(f.panels[0].series[0].x, (std::vector<double>{200, 400}));
  EXPECT_EQ(f.panels[0].series[1].label, "H100");
  EXPECT_EQ(f.panels[0].series[1].x, (std::vector<double>{50, 400}));
  EXPECT_FALSE(f.panels[0].series[0].colour == f.panels[0].series[1].colour);
  // the real-time line first, then one line per device
  ASSERT_EQ(f.panels[1].series.size(), 3u);
  EXPECT_EQ(f.panels[1].series[2].y, (std::vector<double>{0.042, 15.1}));
  ASSERT_TRUE(f.panels[0].y_range.has_value());
  EXPECT_LE(f.panels[0].y_range->lo, 11.0);    // the slowest, in millions per second
  EXPECT_GE(f.panels[0].y_range->hi, 5400.0);  // the fastest
}

// `talus plot` end to end (the tool is built next to this test)
TEST_F(PlotTest, CommandWritesTheThreeFiguresAndRejectsBadInput) {
  const std::string talus = std::string(TALUS_BINARY_DIR) + "/talus";
  ASSERT_TRUE(fs::exists(talus)) << talus << " not built: build the talus target (scripts/test builds everything)";
  for (const char* name : {"ref", "D200"}) {
    sim2real::Run r = synthetic_run(name, 0.05, 2.0e5, -0.02, 1.0e5, 3.0e4, 1.5);
    r.summary.dig_start_s = 0.5;
    r.summary.dig_end_s = 1.5;
    r.summary.loaded_mass_kg = 2700.0;  // the errors of mass and work need them non-zero
    r.summary.work_J = 1.27e5;
    fs::create_directories(dir_ / name);
    sim2real::save_timeseries(dir_ / name / sim2real::kTimeseriesFile, r.series);
    sim2real::save_summary(dir_ / name / sim2real::kSummaryFile, r.summary);
  }
  const std::string profile = std::string(TALUS_SOURCE_DIR) + "/data/piles/default.json";
  const std::string out = file("figures");
  std::string cmd = talus + " plot --runs " + file("D200") + " --ref " + file("ref") + " --pile-profile " +
                    profile + " --out " + out + " 2>/dev/null";
  int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  for (const char* name : {"channels.png", "trajectory.png", "power.png"})
    EXPECT_GT(read_png(out + "/" + name).width, 0) << name;
  // a run named by a particle level is also placed on the resolution figure
  EXPECT_GT(read_png(out + "/resolution.png").width, 0);
  // a run folder that does not exist is bad input: exit code 2
  cmd = talus + " plot --runs " + file("missing") + " --out " + out + " 2>/dev/null";
  status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
}

}  // namespace
}  // namespace talus

namespace talus {
namespace {

// a y label that fits its panel stays one line; a longer "name [unit]" is split into the name
// and the unit, and a line still too long is drawn smaller, never below 0.7
TEST(PlotLayout, LongYLabelsAreSplitThenScaledToTheirPanel) {
  const YLabelLines fits = y_label_lines("speed [m/s]", 400.0);
  EXPECT_EQ(fits.lines, std::vector<std::string>{"speed [m/s]"});
  EXPECT_DOUBLE_EQ(fits.scale, 1.0);
  // 19 characters at 0.6 x 14 px: 160 px, more than a 116 px panel holds
  const YLabelLines split = y_label_lines("traction force [kN]", 116.0);
  EXPECT_EQ(split.lines, (std::vector<std::string>{"traction force", "[kN]"}));
  // "traction force": 14 characters, 118 px, a little more than 0.92 x 116 px: drawn at 0.91
  EXPECT_NEAR(split.scale, 0.92 * 116.0 / (0.6 * 14.0 * 14), 1e-12);
  EXPECT_EQ(y_label_lines("lift force [kN]", 200.0).lines.size(), 1u);
  const YLabelLines scaled = y_label_lines("traction force [kN]", 100.0);
  EXPECT_EQ(scaled.lines.size(), 2u);
  EXPECT_NEAR(scaled.scale, 0.92 * 100.0 / (0.6 * 14.0 * 14), 1e-12);
  const YLabelLines floor = y_label_lines("a label without a unit that is far too long", 50.0);
  EXPECT_EQ(floor.lines.size(), 1u);
  EXPECT_DOUBLE_EQ(floor.scale, 0.7);
}

}  // namespace
}  // namespace talus
