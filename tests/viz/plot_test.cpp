// SPDX-License-Identifier: Apache-2.0
// viz::plot_lines (energy.png of `ido simulate`): the pixels of a plotted line lie where the
// data says, the axes cover the data, bad input is refused with a clear message.
#include "ido/viz/plot.h"


#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "support/png_read.h"
#include "support/test_support.h"

namespace ido::viz {
namespace {

constexpr std::array<std::uint8_t, 3> kMagenta = {200, 0, 200};  // not used by the axes or the palette

bool has_colour(const Image& im, int x, int y, const std::array<std::uint8_t, 3>& c) {
  const auto* p = im.pixel(x, y);
  return p[0] == c[0] && p[1] == c[1] && p[2] == c[2];
}

/// The plot frame found in the picture: the two columns and two rows that are black over more
/// than half the picture's height / width (the axes box; ticks and text are much shorter).
struct Frame {
  int left = -1, right = -1, top = -1, bottom = -1;
};

Frame find_frame(const Image& im) {
  const std::array<std::uint8_t, 3> black = {0, 0, 0};
  Frame f;
  for (int x = 0; x < im.width; ++x) {
    int n = 0;
    for (int y = 0; y < im.height; ++y) n += has_colour(im, x, y, black);
    if (n > im.height / 2) {
      if (f.left < 0) f.left = x;
      f.right = x;
    }
  }
  for (int y = 0; y < im.height; ++y) {
    int n = 0;
    for (int x = 0; x < im.width; ++x) n += has_colour(im, x, y, black);
    if (n > im.width / 2) {
      if (f.top < 0) f.top = y;
      f.bottom = y;
    }
  }
  return f;
}

PlotOptions sized(int width_px, int height_px, std::string title = {}) {
  PlotOptions o;
  o.width_px = width_px;
  o.height_px = height_px;
  o.title = std::move(title);
  return o;
}

struct Pixel {
  int x, y;
};

/// Pixels of colour @p c, leaving out the legend (top-right corner of the frame; short labels).
std::vector<Pixel> series_pixels(const Image& im, const Frame& f, const std::array<std::uint8_t, 3>& c) {
  std::vector<Pixel> out;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x)
      if (has_colour(im, x, y, c) && !(x > f.right - 90 && y < f.top + 30)) out.push_back({x, y});
  return out;
}

TEST(Plot, StraightLinePixelsLieOnTheExpectedLine) {
  // y = 3 − x/2 for x in [0, 10]: the y range [−2, 3] is already on tick multiples (step 1),
  // so the axes span exactly the data and the line joins the frame's top-left corner to its
  // bottom-right corner.
  PlotSeries s{"line", {}, {}, kMagenta};
  for (int i = 0; i <= 10; ++i) {
    s.x.push_back(i);
    s.y.push_back(3.0 - 0.5 * i);
  }
  const Image im = plot_lines(std::span(&s, 1), sized(600, 400));
  ASSERT_EQ(im.width, 600);
  ASSERT_EQ(im.height, 400);
  ASSERT_EQ(im.rgba.size(), 600u * 400u * 4u);
  const Frame f = find_frame(im);
  ASSERT_GE(f.left, 0);
  ASSERT_GT(f.right - f.left, 300);
  ASSERT_GT(f.bottom - f.top, 200);
  const auto px = series_pixels(im, f, kMagenta);
  ASSERT_GT(px.size(), 300u);
  // Every pixel within 1.5 px of the segment (the line is drawn 2 px thick, down-right).
  const double dx = f.right - f.left, dy = f.bottom - f.top, len = std::hypot(dx, dy);
  double worst = 0;
  for (const auto& p : px) {
    const double dist = std::abs((p.x - f.left) * dy - (p.y - f.top) * dx) / len;
    worst = std::max(worst, dist);
  }
  EXPECT_LE(worst, 1.5);
  // And it runs the whole width: every column of the frame has a line pixel.
  std::vector<bool> column(std::size_t(im.width), false);
  for (const auto& p : px) column[std::size_t(p.x)] = true;
  for (int x = f.left; x <= f.right; ++x) EXPECT_TRUE(column[std::size_t(x)]) << "column " << x;
}

TEST(Plot, AxesCoverTheData) {
  // Awkward numbers: x in [−3.3, 7.9], y in [0.37, 12.9]; a second series far below.
  PlotSeries a{"a", {}, {}, kMagenta};
  PlotSeries b{"b", {}, {}, {0, 160, 0}};
  for (int i = 0; i <= 200; ++i) {
    const double x = -3.3 + 11.2 * i / 200.0;
    a.x.push_back(x);
    a.y.push_back(0.37 + 12.53 * std::pow(std::sin(x), 2));
    b.x.push_back(x);
    b.y.push_back(-4.2 + 0.1 * x);
  }
  const std::vector<PlotSeries> series = {a, b};
  PlotOptions o = sized(700, 450, "t");
  o.x_label = "x";
  o.y_label = "y";
  const Image im = plot_lines(series, o);
  const Frame f = find_frame(im);
  ASSERT_GE(f.left, 0);
  int ymin = im.height, ymax = -1, xmin = im.width, xmax = -1;
  for (const auto& colour : {a.rgb, b.rgb}) {
    const auto px = series_pixels(im, f, colour);
    ASSERT_FALSE(px.empty());
    for (const auto& p : px) {
      // Inside the frame (the 2-px pen may reach one pixel past the last line).
      EXPECT_GE(p.x, f.left);
      EXPECT_LE(p.x, f.right + 1);
      EXPECT_GE(p.y, f.top);
      EXPECT_LE(p.y, f.bottom + 1);
      ymin = std::min(ymin, p.y);
      ymax = std::max(ymax, p.y);
      xmin = std::min(xmin, p.x);
      xmax = std::max(xmax, p.x);
    }
  }
  // x is not padded: the data spans the frame's width.
  EXPECT_LE(xmin, f.left + 1);
  EXPECT_GE(xmax, f.right - 1);
  // y is rounded out to ticks only: the data (−4.5 … 12.9) fills most of the height.
  EXPECT_GT(double(ymax - ymin), 0.75 * (f.bottom - f.top));
  // The high series is above the low one everywhere.
  const auto pa = series_pixels(im, f, a.rgb), pb = series_pixels(im, f, b.rgb);
  int lowest_a = -1, highest_b = im.height;
  for (const auto& p : pa) lowest_a = std::max(lowest_a, p.y);
  for (const auto& p : pb) highest_b = std::min(highest_b, p.y);
  EXPECT_LT(lowest_a, highest_b);
}

TEST(Plot, ConstantSeriesIsAHorizontalLineInsideTheFrame) {
  PlotSeries s{"flat", {0, 1, 2, 3}, {5, 5, 5, 5}, kMagenta};
  const Image im = plot_lines(std::span(&s, 1), sized(400, 300));
  const Frame f = find_frame(im);
  const auto px = series_pixels(im, f, kMagenta);
  ASSERT_FALSE(px.empty());
  int lo = im.height, hi = -1;
  for (const auto& p : px) {
    lo = std::min(lo, p.y);
    hi = std::max(hi, p.y);
  }
  EXPECT_LE(hi - lo, 1);  // 2 px thick, one row
  EXPECT_GT(lo, f.top);
  EXPECT_LT(hi, f.bottom);
}

TEST(Plot, BadInputIsRefusedWithAClearMessage) {
  auto message = [](const std::vector<PlotSeries>& s, const PlotOptions& o = {}) -> std::string {
    try {
      (void)plot_lines(s, o);
    } catch (const InvalidInput& e) {
      return e.what();
    }
    return "no error";
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  std::string m = message({{"kinetic", {0, 1, 2}, {1, nan, 3}, {}}});
  EXPECT_NE(m.find("kinetic"), std::string::npos) << m;
  EXPECT_NE(m.find("non-finite"), std::string::npos) << m;
  m = message({{"ok", {0, 1}, {0, 1}, {}}, {"total", {0, inf}, {1, 2}, {}}});
  EXPECT_NE(m.find("total"), std::string::npos) << m;
  EXPECT_NE(m.find("non-finite"), std::string::npos) << m;
  m = message({{"elastic", {0, 1, 2}, {1, 2}, {}}});
  EXPECT_NE(m.find("elastic"), std::string::npos) << m;
  EXPECT_NE(m.find("different lengths"), std::string::npos) << m;
  m = message({});
  EXPECT_NE(m.find("no series"), std::string::npos) << m;
  m = message({{"a", {0, 1}, {0, 1}, {}}}, sized(100, 100));
  EXPECT_NE(m.find("size"), std::string::npos) << m;
}

TEST(Plot, WrittenPngIsThePlottedImage) {
  const auto dir = test::scratch_dir("plot_png");
  PlotSeries s{"e", {0, 1, 2, 3}, {3, 1, 4, 1}, {}};
  const PlotOptions o = sized(320, 200, "Energy");
  write_line_plot(dir / "p.png", std::span(&s, 1), o);
  const Image expected = plot_lines(std::span(&s, 1), o);
  const test::Png back = test::read_png(dir / "p.png");
  EXPECT_EQ(back.w, 320);
  EXPECT_EQ(back.h, 200);
  EXPECT_TRUE(back.rgba == expected.rgba);
}

}  // namespace
}  // namespace ido::viz
