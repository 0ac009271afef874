// SPDX-License-Identifier: Apache-2.0
#pragma once
// Pictures of an evolution (`--snapshots DIR` on `ido segment`, `ido simulate`, `ido drill`):
// numbered PNG files from one fixed camera, so consecutive pictures are comparable.

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "ido/core/math.h"
#include "ido/viz/camera.h"
#include "ido/viz/renderer.h"

namespace ido::cli {

/// Picture size and the camera's viewing angles for SnapshotWriter.
struct SnapshotOptions {
  int width_px = 800;   ///< picture width (pixels), 1..16384
  int height_px = 600;  ///< picture height (pixels), 1..16384
  double azimuth_deg = 30.0;    ///< see viz::Camera::orbit
  double elevation_deg = 20.0;  ///< see viz::Camera::orbit
  viz::Projection projection = viz::Projection::Perspective;
};

/// Parses "WIDTHxHEIGHT" (pixels, each 1..16384). @p what names the argument in the error.
/// @throws ido::InvalidInput otherwise.
[[nodiscard]] std::array<int, 2> parse_picture_size(const std::string& text, std::string_view what);

/// Writes the pictures of one run into a folder as snapshot_0000.png, snapshot_0001.png, …
/// (each written atomically), and remembers which files it wrote.
///
/// The camera is fixed once: by frame() with a box known to contain the whole evolution, or
/// else by the first write(Renderer&) from that renderer's bounds. Every later picture uses
/// the same camera, so sizes and motions compare between pictures.
class SnapshotWriter {
 public:
  /// Prepares @p dir (created if missing). Files of an earlier run that follow the naming
  /// pattern (snapshot_NNNN.png, exactly four digits) are removed so the folder shows one run;
  /// nothing else in the folder is touched.
  /// @throws ido::InvalidInput naming @p argument (e.g. "--snapshots") when @p dir is empty,
  /// exists and is not a folder, cannot be created or is not writable; or when the picture
  /// size is out of range.
  explicit SnapshotWriter(std::filesystem::path dir, const SnapshotOptions& options = {},
                          std::string_view argument = "--snapshots");

  [[nodiscard]] const std::filesystem::path& dir() const { return m_dir; }
  [[nodiscard]] int width() const { return m_options.width_px; }
  [[nodiscard]] int height() const { return m_options.height_px; }

  /// Fixes the camera so that the box [@p lo, @p hi] (mm) fills the picture
  /// (viz::Camera::orbit with the options' angles and projection). Replaces a camera fixed
  /// earlier; call it before the first picture.
  void frame(const Vec3& lo, const Vec3& hi);
  /// Fixes @p camera for all later pictures.
  void set_camera(const viz::Camera& camera) { m_camera = camera; }
  /// The fixed camera, if any.
  [[nodiscard]] const std::optional<viz::Camera>& camera() const { return m_camera; }

  /// Renders @p renderer (which must have been made with width() × height()) with the fixed
  /// camera — fixing it from renderer.bounds() if none is fixed yet — and writes the next
  /// picture. Returns its path.
  /// @throws ido::InvalidInput for a renderer of another size; as viz::Renderer::render and
  /// viz::write_png.
  std::filesystem::path write(viz::Renderer& renderer);
  /// Writes @p image as the next picture (any size; composed pictures). Returns its path.
  /// @throws as viz::write_png.
  std::filesystem::path write(const viz::Image& image);

  /// The files written so far, in order.
  [[nodiscard]] const std::vector<std::filesystem::path>& files() const { return m_files; }
  /// The same as a JSON array of path strings (for report.json "snapshots").
  [[nodiscard]] nlohmann::json files_json() const;

 private:
  std::filesystem::path m_dir;
  SnapshotOptions m_options;
  std::optional<viz::Camera> m_camera;
  std::vector<std::filesystem::path> m_files;
};

/// @p left and @p right side by side in one picture (left's width + right's width, the larger
/// height; uncovered pixels white). Used to show a 3-D view next to a CT slice.
[[nodiscard]] viz::Image side_by_side(const viz::Image& left, const viz::Image& right);

}  // namespace ido::cli
