// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "ido/core/error.h"
#include "ido/core/math.h"
#include "ido/core/memory.h"
#include "ido/geometry/aabb.h"

namespace ido::image {

/// How trilinear sampling treats points outside the voxel grid.
enum class Boundary {
  Clamp,     ///< use the nearest voxel on the border
  Constant,  ///< use the caller's outside value
};

/// A 3D scalar image on a regular grid placed in world space as ITK does (LPS, mm):
///
///   world = origin + direction · (spacing ∘ index)
///
/// Voxel (i, j, k) is stored at i + nx · (j + ny · k) (x fastest, as in ITK and NIfTI).
/// `direction` is a 3×3 matrix whose columns are the unit world directions of the i, j, k
/// axes. Continuous indices put voxel centres at integer values.
template <class T>
class Volume {
 public:
  using value_type = T;

  Volume() = default;

  /// A volume of @p size voxels filled with @p fill. Spacing is in mm per voxel and must be
  /// positive; @p direction must be invertible. @throws ido::InvalidInput otherwise.
  explicit Volume(Index3 size, const Vec3& spacing_mm = Vec3::Ones(),
                  const Vec3& origin_mm = Vec3::Zero(), const Mat3& direction = Mat3::Identity(),
                  T fill = T{})
      : m_size(size), m_spacing(spacing_mm), m_origin(origin_mm), m_direction(direction) {
    check_grid();
    // Reserved, advised for huge pages, then filled: a large volume's first touch then maps
    // 2 MiB per fault instead of 4 KiB (ido/core/memory.h).
    const auto n = static_cast<std::size_t>(size[0] * size[1] * size[2]);
    reserve_advised(m_data, n);
    m_data.assign(n, fill);
  }

  /// A volume of @p size voxels that takes over @p voxels (i fastest, then j, then k) without
  /// copying or first filling them: for a reader that decoded the voxels itself.
  /// @throws ido::InvalidInput as the constructor above, or when the count is not
  /// size[0] · size[1] · size[2].
  Volume(Index3 size, std::vector<T> voxels, const Vec3& spacing_mm, const Vec3& origin_mm, const Mat3& direction)
      : m_size(size), m_spacing(spacing_mm), m_origin(origin_mm), m_direction(direction) {
    check_grid();
    if (voxels.size() != static_cast<std::size_t>(size[0] * size[1] * size[2]))
      throw InvalidInput("volume of " + std::to_string(size[0]) + "×" + std::to_string(size[1]) + "×" +
                         std::to_string(size[2]) + " voxels given " + std::to_string(voxels.size()) + " values");
    m_data = std::move(voxels);
  }

  // ---- grid --------------------------------------------------------------------------
  [[nodiscard]] const Index3& size() const noexcept { return m_size; }
  [[nodiscard]] std::int64_t size(int axis) const noexcept { return m_size[axis]; }
  [[nodiscard]] std::size_t voxel_count() const noexcept { return m_data.size(); }
  [[nodiscard]] bool empty() const noexcept { return m_data.empty(); }
  /// Voxel size in mm along i, j, k.
  [[nodiscard]] const Vec3& spacing() const noexcept { return m_spacing; }
  /// World position (mm) of voxel (0, 0, 0)'s centre.
  [[nodiscard]] const Vec3& origin() const noexcept { return m_origin; }
  [[nodiscard]] const Mat3& direction() const noexcept { return m_direction; }

  void set_spacing(const Vec3& spacing_mm) {
    if (!(spacing_mm.array() > 0.0).all() || !spacing_mm.allFinite())
      throw InvalidInput("volume spacing must be positive and finite");
    m_spacing = spacing_mm;
    update_transform();
  }
  void set_origin(const Vec3& origin_mm) {
    if (!origin_mm.allFinite()) throw InvalidInput("volume origin must be finite");
    m_origin = origin_mm;
  }
  void set_direction(const Mat3& direction) {
    m_direction = direction;
    update_transform();
  }

  /// True when @p other has the same size and, within @p tol_mm, the same placement.
  template <class U>
  [[nodiscard]] bool same_grid(const Volume<U>& other, double tol_mm = 1e-6) const {
    return m_size == other.size() && (m_spacing - other.spacing()).cwiseAbs().maxCoeff() <= tol_mm &&
           (m_origin - other.origin()).cwiseAbs().maxCoeff() <= tol_mm &&
           (m_direction - other.direction()).cwiseAbs().maxCoeff() <= 1e-6;
  }

  /// An empty volume of another voxel type on the same grid, filled with @p fill.
  template <class U>
  [[nodiscard]] Volume<U> like(U fill = U{}) const {
    return Volume<U>(m_size, m_spacing, m_origin, m_direction, fill);
  }

  // ---- voxels ------------------------------------------------------------------------
  [[nodiscard]] std::size_t linear_index(std::int64_t i, std::int64_t j,
                                         std::int64_t k) const noexcept {
    return static_cast<std::size_t>(i + m_size[0] * (j + m_size[1] * k));
  }
  [[nodiscard]] bool contains(std::int64_t i, std::int64_t j, std::int64_t k) const noexcept {
    return i >= 0 && j >= 0 && k >= 0 && i < m_size[0] && j < m_size[1] && k < m_size[2];
  }
  /// Unchecked access; (i, j, k) must be inside the grid.
  [[nodiscard]] T& operator()(std::int64_t i, std::int64_t j, std::int64_t k) noexcept {
    return m_data[linear_index(i, j, k)];
  }
  [[nodiscard]] const T& operator()(std::int64_t i, std::int64_t j,
                                    std::int64_t k) const noexcept {
    return m_data[linear_index(i, j, k)];
  }
  /// Checked access. @throws ido::InvalidInput when (i, j, k) is outside the grid.
  [[nodiscard]] const T& at(std::int64_t i, std::int64_t j, std::int64_t k) const {
    if (!contains(i, j, k)) throw InvalidInput("voxel index outside the volume");
    return (*this)(i, j, k);
  }
  [[nodiscard]] std::vector<T>& data() noexcept { return m_data; }
  [[nodiscard]] const std::vector<T>& data() const noexcept { return m_data; }

  // ---- transforms --------------------------------------------------------------------
  /// World position (mm) of a continuous index.
  [[nodiscard]] Vec3 index_to_world(const Vec3& index) const noexcept {
    return m_origin + m_index_to_world * index;
  }
  /// Continuous index of a world position (mm).
  [[nodiscard]] Vec3 world_to_index(const Vec3& world_mm) const noexcept {
    return m_world_to_index * (world_mm - m_origin);
  }
  /// The linear map from index offsets to world offsets: direction · diag(spacing).
  [[nodiscard]] const Mat3& index_to_world_matrix() const noexcept { return m_index_to_world; }
  [[nodiscard]] const Mat3& world_to_index_matrix() const noexcept { return m_world_to_index; }

  /// Axis-aligned world bounds (mm) of the voxel centres' hull.
  [[nodiscard]] geometry::Aabb world_bounds() const {
    geometry::Aabb b;
    for (int c = 0; c < 8; ++c)
      b.extend(index_to_world(Vec3((c & 1) ? double(m_size[0] - 1) : 0.0, (c & 2) ? double(m_size[1] - 1) : 0.0,
                                   (c & 4) ? double(m_size[2] - 1) : 0.0)));
    return b;
  }

  /// Continuous-index bounds of the world box @p world_mm: the index-space box of its eight
  /// corners (for a grid rotated against the world axes, a box holding the rotated one).
  [[nodiscard]] geometry::Aabb index_bounds(const geometry::Aabb& world_mm) const {
    geometry::Aabb b;
    for (int c = 0; c < 8; ++c)
      b.extend(world_to_index(Vec3((c & 1) ? world_mm.max.x() : world_mm.min.x(), (c & 2) ? world_mm.max.y() : world_mm.min.y(),
                                   (c & 4) ? world_mm.max.z() : world_mm.min.z())));
    return b;
  }

  // ---- sampling ----------------------------------------------------------------------
  /// Trilinear interpolation at a continuous index. Outside the grid, Clamp uses the
  /// border value, Constant returns @p outside.
  [[nodiscard]] double sample_index(const Vec3& index, Boundary boundary = Boundary::Clamp,
                                    double outside = 0.0) const noexcept {
    if (m_data.empty()) return outside;
    double f[3];
    std::int64_t i0[3];
    for (int a = 0; a < 3; ++a) {
      const double hi = double(m_size[a] - 1);
      double x = index[a];
      if (!(x >= 0.0 && x <= hi)) {
        if (boundary == Boundary::Constant) {
          // Within half a voxel of the border, a point still belongs to the border voxel.
          if (!(x >= -0.5 && x <= hi + 0.5)) return outside;
        }
        x = std::clamp(std::isnan(x) ? 0.0 : x, 0.0, hi);
      }
      // x is in [0, hi] here, where truncation is floor (and much cheaper than the call).
      i0[a] = std::min<std::int64_t>(static_cast<std::int64_t>(x), std::max<std::int64_t>(m_size[a] - 2, 0));
      f[a] = x - double(i0[a]);
    }
    const std::int64_t i1[3] = {std::min(i0[0] + 1, m_size[0] - 1), std::min(i0[1] + 1, m_size[1] - 1),
                                std::min(i0[2] + 1, m_size[2] - 1)};
    auto v = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
      return static_cast<double>((*this)(i, j, k));
    };
    const double c00 = v(i0[0], i0[1], i0[2]) * (1 - f[0]) + v(i1[0], i0[1], i0[2]) * f[0];
    const double c10 = v(i0[0], i1[1], i0[2]) * (1 - f[0]) + v(i1[0], i1[1], i0[2]) * f[0];
    const double c01 = v(i0[0], i0[1], i1[2]) * (1 - f[0]) + v(i1[0], i0[1], i1[2]) * f[0];
    const double c11 = v(i0[0], i1[1], i1[2]) * (1 - f[0]) + v(i1[0], i1[1], i1[2]) * f[0];
    const double c0 = c00 * (1 - f[1]) + c10 * f[1];
    const double c1 = c01 * (1 - f[1]) + c11 * f[1];
    return c0 * (1 - f[2]) + c1 * f[2];
  }

  /// Trilinear interpolation at a world position (mm); see sample_index.
  [[nodiscard]] double sample(const Vec3& world_mm, Boundary boundary = Boundary::Clamp,
                              double outside = 0.0) const noexcept {
    return sample_index(world_to_index(world_mm), boundary, outside);
  }

 private:
  void check_grid() {
    for (int a = 0; a < 3; ++a) {
      if (m_size[a] < 0) throw InvalidInput("volume size must not be negative");
      if (!(m_spacing[a] > 0.0) || !std::isfinite(m_spacing[a]))
        throw InvalidInput("volume spacing must be positive and finite");
    }
    if (!m_origin.allFinite()) throw InvalidInput("volume origin must be finite");
    update_transform();
  }
  void update_transform() {
    m_index_to_world = m_direction * m_spacing.asDiagonal();
    const double det = m_index_to_world.determinant();
    if (!(std::abs(det) > 1e-12) || !std::isfinite(det))
      throw InvalidInput("volume direction matrix is singular");
    m_world_to_index = m_index_to_world.inverse();
  }

  Index3 m_size{0, 0, 0};
  Vec3 m_spacing = Vec3::Ones();
  Vec3 m_origin = Vec3::Zero();
  Mat3 m_direction = Mat3::Identity();
  Mat3 m_index_to_world = Mat3::Identity();
  Mat3 m_world_to_index = Mat3::Identity();
  std::vector<T> m_data;
};

}  // namespace ido::image
