// SPDX-License-Identifier: Apache-2.0
#pragma once

#include "ido/sim/fem_common.h"

namespace ido::sim {

/// Stable Neo-Hookean elasticity (Smith, de Goes & Kim, "Stable Neo-Hookean Flesh
/// Simulation", ACM TOG 2018, the variant without the log term):
/// Ψ = ½ μ (I_C − 3) + ½ λ' (J − α)² − ½ λ' (1 − α)², λ' = λ + μ, α = 1 + μ/λ',
/// so that it linearises to the given E, ν, has zero stress and energy at rest and stays
/// finite and well defined for inverted elements (no log J).
/// P = μ F + λ' (J − α) cof(F). Stiffness: the exact tangent, projected to be positive
/// semi-definite by default (set_definite_stiffness(false) gives the exact one).
class NeoHookeanFem final : public TetFemModel {
 public:
  NeoHookeanFem(std::vector<Tet> tets, std::span<const Vec3> rest_positions_mm,
                const ElasticMaterial& material)
      : TetFemModel(std::move(tets), rest_positions_mm, material) {
    m_definite = true;
  }
  [[nodiscard]] std::string_view kind() const override { return "neo_hookean_fem"; }

 protected:
  [[nodiscard]] double energy_density(std::size_t e, const Mat3& F) const override;
  [[nodiscard]] Mat3 first_piola(std::size_t e, const Mat3& F) const override;
  [[nodiscard]] Mat3 dP_dF(std::size_t e, const Mat3& F, const Mat3& dF) const override;
};

}  // namespace ido::sim
