// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/SparseCore>

#include "ido/core/math.h"
#include "ido/sim/particles.h"

namespace ido::sim {

/// Row and column particle indices of one 3×3 block of a stiffness matrix.
struct BlockIndex {
  std::int32_t row = 0;
  std::int32_t col = 0;
};

/// Per-element mechanical state, for output: one entry per element of a model.
struct ElementFields {
  std::vector<Mat3> green_strain;      ///< E = ½(FᵀF − I), dimensionless
  std::vector<Mat3> cauchy_stress_pa;  ///< σ = P Fᵀ / det F, Pa
  std::vector<double> von_mises_pa;    ///< √(3/2 s:s), s = deviatoric part of σ, Pa
};

/// A force model: a set of relations of one kind (springs, tetrahedra, clusters,
/// neighbourhoods) over a world's particles, with its material. It gives forces (N),
/// elastic energy (mJ = N·mm) and, when it can, its stiffness K = −∂f/∂x (N/mm) as 3×3
/// blocks for implicit integration. A model is used by one thread at a time (one world).
class ForceModel {
 public:
  virtual ~ForceModel() = default;
  ForceModel() = default;
  ForceModel(const ForceModel&) = delete;
  ForceModel& operator=(const ForceModel&) = delete;
  ForceModel(ForceModel&&) = default;
  ForceModel& operator=(ForceModel&&) = default;

  /// Short name of the model kind, e.g. "corotational_fem".
  [[nodiscard]] virtual std::string_view kind() const = 0;
  /// Adds this model's forces (N) at the particles' current positions and velocities to
  /// @p forces_n (one entry per particle). Deterministic whether @p threaded or not.
  virtual void add_forces(const Particles& particles, std::span<Vec3> forces_n,
                          bool threaded) const = 0;
  /// Elastic energy (mJ = N·mm) at the current positions; 0 at the rest shape.
  [[nodiscard]] virtual double energy(const Particles& particles) const = 0;

  /// The blocks this model's stiffness has, in a fixed order (empty: no stiffness, the
  /// model is treated explicitly by implicit integrators).
  [[nodiscard]] virtual std::vector<BlockIndex> stiffness_pattern() const { return {}; }
  /// Values of the blocks of stiffness_pattern() (N/mm) at the current positions, written
  /// to @p blocks (same size and order as the pattern).
  virtual void stiffness_blocks(const Particles& particles, std::span<Mat3> blocks,
                                bool threaded) const;
  /// Adds this model's stiffness (N/mm) at the current positions into an assembled block
  /// matrix: block k of stiffness_pattern() is added to @p values[@p slots[k]], or skipped
  /// when slots[k] < 0 (e.g. a block on a fixed particle). The additions happen in pattern
  /// order whether @p threaded or not, so the sums are deterministic. The default computes
  /// stiffness_blocks() into a scratch buffer; models override it to skip the buffer.
  /// Implicit Euler stores only the upper block triangle (it skips block (a, b) when the
  /// transposed block (b, a) is the stored one), so the pattern must be symmetric and the
  /// blocks satisfy K_ba = K_abᵀ, as any energy's Hessian does.
  virtual void add_stiffness_to(const Particles& particles, std::span<const std::int32_t> slots,
                                std::span<Mat3> values, bool threaded) const;
  /// True when stiffness_pattern() is non-empty.
  [[nodiscard]] bool has_stiffness() const { return !stiffness_pattern().empty(); }

  /// Adds K·dx (N) to @p out, K at the current positions. Slow path (assembles blocks);
  /// implicit integration uses the World's cached assembly instead.
  void add_stiffness_product(const Particles& particles, std::span<const Vec3> dx_mm,
                             std::span<Vec3> out_n) const;
  /// K as a sparse (3n × 3n) matrix, N/mm.
  [[nodiscard]] Eigen::SparseMatrix<double> stiffness_matrix(const Particles& particles) const;

  /// Per-element strain and stress for output, if the model has elements.
  [[nodiscard]] virtual std::optional<ElementFields> element_fields(const Particles&) const {
    return std::nullopt;
  }
};

}  // namespace ido::sim
