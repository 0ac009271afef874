// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <vector>

#include "ido/core/math.h"
#include "ido/sim/force_model.h"

namespace ido::sim {

/// Which deformations the goal shape may take (Müller, Heidelberger, Teschner & Gross,
/// "Meshless Deformations Based on Shape Matching", SIGGRAPH 2005, §3–4).
enum class ShapeMatchingMode { Rigid, Linear, Quadratic };

struct ShapeMatchingOptions {
  ShapeMatchingMode mode = ShapeMatchingMode::Rigid;
  double beta = 0.5;                 ///< blend of the linear / quadratic fit with R, [0, 1]
  bool preserve_volume = true;       ///< Linear: scale A by det(A)^(−1/3)
  double stiffness_per_s2 = 1e4;     ///< k in f_i = k m_i (g_i − x_i), 1/s²
};

/// Shape matching as a force model: each cluster (a set of particles, clusters may
/// overlap) finds its best rigid / linear / quadratic match of the rest shape, giving goal
/// positions g_i; particle i gets f_i = k m_i (g_i − x_i) per cluster it belongs to
/// (the paper's α/h² pull written as a force), energy Σ ½ k m_i ‖g_i − x_i‖².
/// No stiffness: implicit integrators treat it explicitly.
class ShapeMatching final : public ForceModel {
 public:
  /// Rest shape = current positions of @p particles. @throws ido::InvalidInput for empty
  /// clusters, bad indices, fewer than 4 non-coplanar particles in a Linear/Quadratic
  /// cluster, or options out of range.
  ShapeMatching(const Particles& particles, std::vector<std::vector<std::int32_t>> clusters,
                const ShapeMatchingOptions& options = {});

  [[nodiscard]] std::string_view kind() const override { return "shape_matching"; }
  void add_forces(const Particles& particles, std::span<Vec3> forces_n,
                  bool threaded) const override;
  [[nodiscard]] double energy(const Particles& particles) const override;
  /// Goal positions (mm) of every (cluster, member) pair, cluster-major.
  [[nodiscard]] std::vector<Vec3> goal_positions(const Particles& particles) const;
  [[nodiscard]] const std::vector<std::vector<std::int32_t>>& clusters() const noexcept {
    return m_clusters;
  }
  [[nodiscard]] const ShapeMatchingOptions& options() const noexcept { return m_options; }
  /// Sets the stiffness k (1/s²) between steps. @throws ido::InvalidInput naming
  /// stiffness_per_s2 unless ≥ 0 and finite (the model is unchanged then).
  void set_stiffness(double stiffness_per_s2);
  /// Sets the blend β of the linear / quadratic fit with the rotation between steps.
  /// @throws ido::InvalidInput naming beta unless in [0, 1].
  void set_beta(double beta);

 private:
  struct Cluster;
  void goals(const Particles& particles, std::size_t c, std::span<Vec3> out) const;
  std::vector<std::vector<std::int32_t>> m_clusters;
  ShapeMatchingOptions m_options;
  std::vector<Vec3> m_rest_centre;
  std::vector<std::vector<Vec3>> m_q;            // rest offsets per cluster member
  std::vector<Mat3> m_aqq_inv;                   // linear
  std::vector<Eigen::Matrix<double, 9, 9>> m_aqq9_inv;  // quadratic
  mutable std::vector<Eigen::Quaterniond> m_rotation;
  std::vector<std::int32_t> m_slot_offset;       // start of cluster c in the flat slot list
  std::vector<std::int32_t> m_offsets, m_sources;   // gather per particle
};

/// Overlapping clusters over a regular grid of cell size @p cell_mm: one cluster per
/// occupied cell, holding every particle within 1.5 cells of the cell's centre (in the
/// spirit of the paper's overlapping clusters, §4.3). Clusters with < 4 particles are dropped.
[[nodiscard]] std::vector<std::vector<std::int32_t>> grid_clusters(std::span<const Vec3> positions_mm,
                                                                   double cell_mm);

}  // namespace ido::sim
