// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "ido/core/math.h"

namespace ido::view {

/// A rectangle of the window in pixels, (x, y) its top-left corner.
struct PixelRect {
  double x = 0, y = 0, width = 0, height = 0;
  [[nodiscard]] bool contains(double px, double py) const {
    return px >= x && py >= y && px < x + width && py < y + height;
  }
};

/// How one orthogonal CT slice is laid out in a view: the slice (voxel index plane normal to
/// `axis`) is scaled by its spacing so that millimetres are square, fitted into the view and
/// centred. In-plane axes: axial (axis 2) shows i left→right and j top→bottom; coronal
/// (axis 1) i left→right and k bottom→top; sagittal (axis 0) j left→right and k bottom→top.
/// The volume's direction matrix is not applied: the slice is shown in index order, as
/// viz::Renderer::slice_camera shows it.
class SliceView {
 public:
  /// @p axis 0, 1 or 2; @p size and @p spacing_mm of the volume; @p rect the view (pixels).
  SliceView(int axis, const Index3& size, const Vec3& spacing_mm, const PixelRect& rect);

  [[nodiscard]] int axis() const { return m_axis; }
  /// The index axes shown horizontally and vertically.
  [[nodiscard]] int u_axis() const { return m_u; }
  [[nodiscard]] int v_axis() const { return m_v; }
  [[nodiscard]] const PixelRect& rect() const { return m_rect; }
  /// Pixels per millimetre.
  [[nodiscard]] double scale_px_per_mm() const { return m_scale; }

  /// The in-plane voxel indices (along u_axis(), v_axis()) under pixel position
  /// (@p x_px, @p y_px), or nothing outside the slice.
  [[nodiscard]] std::optional<std::array<std::int64_t, 2>> voxel_at(double x_px, double y_px) const;
  /// The pixel position of continuous in-plane index coordinates (@p u, @p v); a voxel's
  /// centre is at integer coordinates.
  [[nodiscard]] std::array<double, 2> pixel_of(double u, double v) const;
  /// The 4×4 matrix taking in-plane index coordinates (u, v, 0, 1) to the view's normalised
  /// device coordinates (x, y in −1..1 across the view rectangle).
  [[nodiscard]] Mat4 ndc_from_index() const;

 private:
  int m_axis, m_u, m_v;
  bool m_v_up;
  Index3 m_size;
  Vec3 m_spacing;
  PixelRect m_rect;
  double m_scale = 1.0;
  double m_x0 = 0.0, m_y0 = 0.0;  // pixel position of the slice's corner at index (−0.5, −0.5)
};

}  // namespace ido::view
