// SPDX-License-Identifier: Apache-2.0
#include "ido/view/slice_view.h"

#include <algorithm>
#include <cmath>

#include "ido/core/error.h"

namespace ido::view {

SliceView::SliceView(int axis, const Index3& size, const Vec3& spacing_mm, const PixelRect& rect)
    : m_axis(axis), m_size(size), m_spacing(spacing_mm), m_rect(rect) {
  if (axis < 0 || axis > 2) throw InvalidInput("slice axis must be 0, 1 or 2");
  m_u = axis == 0 ? 1 : 0;
  m_v = axis == 2 ? 1 : 2;
  m_v_up = axis != 2;
  const double w_mm = double(size[std::size_t(m_u)]) * spacing_mm[m_u];
  const double h_mm = double(size[std::size_t(m_v)]) * spacing_mm[m_v];
  m_scale = std::max(1e-9, std::min(rect.width / std::max(w_mm, 1e-9), rect.height / std::max(h_mm, 1e-9)));
  m_x0 = rect.x + 0.5 * (rect.width - w_mm * m_scale);
  m_y0 = m_v_up ? rect.y + 0.5 * (rect.height + h_mm * m_scale)   // the corner at v = −0.5 is at the bottom
                : rect.y + 0.5 * (rect.height - h_mm * m_scale);
}

std::array<double, 2> SliceView::pixel_of(double u, double v) const {
  const double x = m_x0 + (u + 0.5) * m_spacing[m_u] * m_scale;
  const double dy = (v + 0.5) * m_spacing[m_v] * m_scale;
  return {x, m_v_up ? m_y0 - dy : m_y0 + dy};
}

std::optional<std::array<std::int64_t, 2>> SliceView::voxel_at(double x_px, double y_px) const {
  const double u = (x_px - m_x0) / (m_spacing[m_u] * m_scale) - 0.5;
  const double v = (m_v_up ? m_y0 - y_px : y_px - m_y0) / (m_spacing[m_v] * m_scale) - 0.5;
  const auto iu = static_cast<std::int64_t>(std::floor(u + 0.5));
  const auto iv = static_cast<std::int64_t>(std::floor(v + 0.5));
  if (iu < 0 || iv < 0 || iu >= m_size[std::size_t(m_u)] || iv >= m_size[std::size_t(m_v)]) return std::nullopt;
  return std::array<std::int64_t, 2>{iu, iv};
}

Mat4 SliceView::ndc_from_index() const {
  // index → pixel: x = ax·u + bx, y = ay·v + by; pixel → NDC over the rectangle.
  const double ax = m_spacing[m_u] * m_scale, bx = m_x0 + 0.5 * ax;
  const double ay = (m_v_up ? -1.0 : 1.0) * m_spacing[m_v] * m_scale, by = m_y0 + 0.5 * ay;
  Mat4 m = Mat4::Identity();
  m(0, 0) = 2.0 * ax / m_rect.width;
  m(0, 3) = 2.0 * (bx - m_rect.x) / m_rect.width - 1.0;
  m(1, 1) = -2.0 * ay / m_rect.height;
  m(1, 3) = 1.0 - 2.0 * (by - m_rect.y) / m_rect.height;
  m(2, 2) = 0.0;
  return m;
}

}  // namespace ido::view
