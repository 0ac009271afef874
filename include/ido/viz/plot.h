// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "ido/viz/renderer.h"

namespace ido::viz {

/// One line of a plot: points (x[i], y[i]) joined in order.
struct PlotSeries {
  std::string label;
  std::vector<double> x;
  std::vector<double> y;
  std::array<std::uint8_t, 3> rgb = {0, 0, 0};   ///< all zero: pick from a built-in palette
};

struct PlotOptions {
  int width_px = 900;
  int height_px = 540;
  std::string title;
  std::string x_label;
  std::string y_label;
};

/// Rasterises a line plot with axes, "nice" tick marks and numbers, axis labels, a title
/// and a legend, white background. Text uses a built-in 5×7 bitmap font (digits, letters
/// shown upper-case, a few symbols) because no text-rendering library is packaged for the
/// project; characters outside the font are drawn as blanks.
/// @throws ido::InvalidInput for sizes below 200×150 px, no series, x / y of different
/// lengths or non-finite values.
[[nodiscard]] Image plot_lines(std::span<const PlotSeries> series, const PlotOptions& options = {});

/// plot_lines() then write_png(), atomically.
void write_line_plot(const std::filesystem::path& path, std::span<const PlotSeries> series,
                     const PlotOptions& options = {});

}  // namespace ido::viz
