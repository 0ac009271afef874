// SPDX-License-Identifier: Apache-2.0
// A small line-plot rasteriser written for ido (axes, ticks, legend, several series) with
// a hand-made 5×7 bitmap font, since no text library is packaged for the project.
#include "ido/viz/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "ido/core/error.h"

namespace ido::viz {

namespace {

using Rgb = std::array<std::uint8_t, 3>;

// 5×7 glyphs, one byte per row, bit 4 = leftmost column.
struct Glyph {
  char c;
  std::uint8_t rows[7];
};
constexpr Glyph kFont[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}}, {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}}, {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}}, {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}}, {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}}, {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}}, {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}}, {'D', {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}}, {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}}, {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}}, {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}}, {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}}, {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}}, {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}}, {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}}, {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04}}, {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}}, {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}}, {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}}, {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}}, {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}}, {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
};

const Glyph* glyph(char c) {
  if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
  for (const auto& g : kFont)
    if (g.c == c) return &g;
  return nullptr;
}

constexpr Rgb kPalette[] = {{31, 119, 180}, {214, 39, 40}, {44, 160, 44}, {255, 127, 14},
                            {148, 103, 189}, {140, 86, 75}, {227, 119, 194}, {127, 127, 127}};

struct Canvas {
  Image img;
  void put(int x, int y, const Rgb& c) {
    if (x < 0 || y < 0 || x >= img.width || y >= img.height) return;
    auto* p = img.rgba.data() + 4 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(img.width) +
                                     static_cast<std::size_t>(x));
    p[0] = c[0];
    p[1] = c[1];
    p[2] = c[2];
    p[3] = 255;
  }
  void line(int x0, int y0, int x1, int y1, const Rgb& c, int thick = 1) {
    // Bresenham (1965)
    const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
    const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
    int err = dx + dy;
    for (;;) {
      for (int a = 0; a < thick; ++a)
        for (int b = 0; b < thick; ++b) put(x0 + a, y0 + b, c);
      if (x0 == x1 && y0 == y1) break;
      const int e2 = 2 * err;
      if (e2 >= dy) {
        err += dy;
        x0 += sx;
      }
      if (e2 <= dx) {
        err += dx;
        y0 += sy;
      }
    }
  }
  void rect(int x0, int y0, int x1, int y1, const Rgb& c) {
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) put(x, y, c);
  }
  /// Text with its top-left corner at (x, y); @p scale pixels per font pixel.
  void text(int x, int y, const std::string& s, const Rgb& c, int scale = 1, bool vertical = false) {
    for (std::size_t k = 0; k < s.size(); ++k) {
      const Glyph* g = glyph(s[k]);
      const int off = static_cast<int>(k) * 6 * scale;
      if (g)
        for (int r = 0; r < 7; ++r)
          for (int col = 0; col < 5; ++col)
            if (g->rows[r] & (0x10 >> col))
              for (int a = 0; a < scale; ++a)
                for (int b = 0; b < scale; ++b) {
                  if (vertical)  // rotated 90° counter-clockwise, reading bottom to top
                    put(x + r * scale + b, y - off - col * scale - a, c);
                  else
                    put(x + off + col * scale + a, y + r * scale + b, c);
                }
    }
  }
};

int text_width(const std::string& s, int scale = 1) { return static_cast<int>(s.size()) * 6 * scale; }

/// Tick step 1, 2 or 5 × 10^k giving about @p target intervals.
double nice_step(double range, int target) {
  const double raw = range / target;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10.0 * p;
}

std::string tick_label(double v, double step) {
  if (std::abs(v) < 1e-12 * step) v = 0.0;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

}  // namespace

Image plot_lines(std::span<const PlotSeries> series, const PlotOptions& o) {
  if (o.width_px < 200 || o.height_px < 150 || o.width_px > 8192 || o.height_px > 8192)
    throw InvalidInput("plot: size must be within 200×150 .. 8192×8192 px");
  if (series.empty()) throw InvalidInput("plot: no series");
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
  for (const auto& s : series) {
    if (s.x.size() != s.y.size())
      throw InvalidInput("plot: series '" + s.label + "' has x and y of different lengths");
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i]))
        throw InvalidInput("plot: series '" + s.label + "' has a non-finite value");
      xmin = std::min(xmin, s.x[i]);
      xmax = std::max(xmax, s.x[i]);
      ymin = std::min(ymin, s.y[i]);
      ymax = std::max(ymax, s.y[i]);
    }
  }
  if (xmin > xmax) xmin = 0, xmax = 1, ymin = 0, ymax = 1;
  if (xmax - xmin <= 0.0) xmax = xmin + 1.0;
  if (ymax - ymin <= 1e-12 * std::max(std::abs(ymax), 1.0)) {
    const double pad = std::max(std::abs(ymax) * 0.05, 1e-9);
    ymin -= pad;
    ymax += pad;
  }
  const double ystep = nice_step(ymax - ymin, 6), xstep = nice_step(xmax - xmin, 8);
  ymin = std::floor(ymin / ystep) * ystep;
  ymax = std::ceil(ymax / ystep) * ystep;

  Canvas cv;
  cv.img.width = o.width_px;
  cv.img.height = o.height_px;
  cv.img.rgba.assign(static_cast<std::size_t>(o.width_px) * static_cast<std::size_t>(o.height_px) * 4, 255);
  const Rgb black{0, 0, 0}, grey{220, 220, 220}, dark{90, 90, 90};
  const int left = 90, right = o.width_px - 20, top = 40, bottom = o.height_px - 60;
  auto px = [&](double x) { return left + static_cast<int>(std::lround((x - xmin) / (xmax - xmin) * (right - left))); };
  auto py = [&](double y) { return bottom - static_cast<int>(std::lround((y - ymin) / (ymax - ymin) * (bottom - top))); };

  for (double y = ymin; y <= ymax + 0.5 * ystep; y += ystep) {
    const int yy = py(y);
    cv.line(left, yy, right, yy, grey);
    cv.line(left - 5, yy, left, yy, black);
    const auto s = tick_label(y, ystep);
    cv.text(left - 8 - text_width(s), yy - 3, s, dark);
  }
  for (double x = std::ceil(xmin / xstep) * xstep; x <= xmax + 1e-9 * xstep; x += xstep) {
    const int xx = px(x);
    cv.line(xx, top, xx, bottom, grey);
    cv.line(xx, bottom, xx, bottom + 5, black);
    const auto s = tick_label(x, xstep);
    cv.text(xx - text_width(s) / 2, bottom + 9, s, dark);
  }
  cv.line(left, top, left, bottom, black);
  cv.line(left, bottom, right, bottom, black);
  cv.line(right, top, right, bottom, black);
  cv.line(left, top, right, top, black);
  if (!o.title.empty()) cv.text((left + right - text_width(o.title, 2)) / 2, 10, o.title, black, 2);
  if (!o.x_label.empty())
    cv.text((left + right - text_width(o.x_label)) / 2, bottom + 28, o.x_label, black);
  if (!o.y_label.empty()) cv.text(8, (top + bottom + text_width(o.y_label)) / 2, o.y_label, black, 1, true);

  for (std::size_t k = 0; k < series.size(); ++k) {
    const auto& s = series[k];
    const Rgb c = (s.rgb == Rgb{0, 0, 0}) ? kPalette[k % std::size(kPalette)] : s.rgb;
    for (std::size_t i = 1; i < s.x.size(); ++i)
      cv.line(px(s.x[i - 1]), py(s.y[i - 1]), px(s.x[i]), py(s.y[i]), c, 2);
    if (s.x.size() == 1) cv.rect(px(s.x[0]) - 1, py(s.y[0]) - 1, px(s.x[0]) + 1, py(s.y[0]) + 1, c);
  }
  // Legend, top right.
  int lw = 0;
  for (const auto& s : series) lw = std::max(lw, text_width(s.label));
  const int lx = right - lw - 40, ly = top + 8;
  cv.rect(lx - 6, ly - 6, right - 6, ly + 14 * static_cast<int>(series.size()), Rgb{255, 255, 255});
  for (std::size_t k = 0; k < series.size(); ++k) {
    const Rgb c = (series[k].rgb == Rgb{0, 0, 0}) ? kPalette[k % std::size(kPalette)] : series[k].rgb;
    const int y = ly + 14 * static_cast<int>(k);
    cv.rect(lx, y + 2, lx + 18, y + 4, c);
    cv.text(lx + 24, y, series[k].label, black);
  }
  return cv.img;
}

void write_line_plot(const std::filesystem::path& path, std::span<const PlotSeries> series,
                     const PlotOptions& options) {
  write_png(path, plot_lines(series, options));
}

}  // namespace ido::viz
