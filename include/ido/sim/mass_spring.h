// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/sim/force_model.h"

namespace ido::sim {

/// One spring between two particles.
struct Spring {
  std::int32_t a = 0;
  std::int32_t b = 0;
  double rest_length_mm = 0.0;        ///< > 0
  double stiffness_n_per_mm = 0.0;    ///< ≥ 0
  double damping_n_s_per_mm = 0.0;    ///< ≥ 0, acts on the relative velocity along the spring
};

/// Hookean springs with damping along the spring:
/// f_a = −[k (l − L₀) + c (v_a − v_b)·n] n, n = (x_a − x_b)/l, f_b = −f_a;
/// energy ½ k (l − L₀)². Stiffness is the exact Hessian
/// k [n nᵀ + (1 − L₀/l)(I − n nᵀ)] (e.g. Baraff & Witkin 1998).
class MassSpring final : public ForceModel {
 public:
  /// @throws ido::InvalidInput for negative indices, a = b, non-positive rest length or
  /// negative stiffness / damping (naming the spring).
  explicit MassSpring(std::vector<Spring> springs);
  /// Springs along the unique edges of @p mesh, rest lengths from the mesh (vertex i of the
  /// mesh is particle @p first_particle + i).
  static MassSpring from_tet_edges(const geometry::TetMesh& mesh, std::int32_t first_particle,
                                   double stiffness_n_per_mm, double damping_n_s_per_mm = 0.0);

  [[nodiscard]] std::string_view kind() const override { return "mass_spring"; }
  void add_forces(const Particles& particles, std::span<Vec3> forces_n,
                  bool threaded) const override;
  [[nodiscard]] double energy(const Particles& particles) const override;
  [[nodiscard]] std::vector<BlockIndex> stiffness_pattern() const override;
  void stiffness_blocks(const Particles& particles, std::span<Mat3> blocks,
                        bool threaded) const override;
  [[nodiscard]] const std::vector<Spring>& springs() const noexcept { return m_springs; }
  /// Sets every spring's stiffness k (N/mm) between steps. @throws ido::InvalidInput naming
  /// stiffness_n_per_mm unless ≥ 0 and finite (the model is unchanged then).
  void set_stiffness(double stiffness_n_per_mm);
  /// Sets every spring's damping c (N·s/mm) between steps. @throws ido::InvalidInput naming
  /// damping_n_s_per_mm unless ≥ 0 and finite.
  void set_damping(double damping_n_s_per_mm);

 private:
  std::vector<Spring> m_springs;
  std::vector<std::int32_t> m_offsets;   // gather: per particle, contributions
  std::vector<std::int32_t> m_sources;
};

}  // namespace ido::sim
