// SPDX-License-Identifier: Apache-2.0
#pragma once

#include "ido/sim/fem_common.h"

namespace ido::sim {

/// Linear (small-strain) elasticity on linear tetrahedra: ε = ½(F + Fᵀ) − I,
/// P = σ = 2μ ε + λ tr(ε) I, Ψ = μ ε:ε + ½ λ tr²(ε). Not rotation invariant; constant
/// stiffness. Use it for small displacements (explicit or implicit).
class LinearFem final : public TetFemModel {
 public:
  using TetFemModel::TetFemModel;
  [[nodiscard]] std::string_view kind() const override { return "linear_fem"; }

 protected:
  [[nodiscard]] double energy_density(std::size_t e, const Mat3& F) const override;
  [[nodiscard]] Mat3 first_piola(std::size_t e, const Mat3& F) const override;
  [[nodiscard]] Mat3 dP_dF(std::size_t e, const Mat3& F, const Mat3& dF) const override;
  void element_stiffness(std::size_t e, const Mat3& F, const std::array<Vec3, 4>& b,
                         std::span<Mat3, 16> out) const override;
};

}  // namespace ido::sim
