// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <limits>
#include <vector>

#include "ido/sim/fem_common.h"

namespace ido::sim {

/// Corotational linear elasticity (Müller & Gross, "Interactive Virtual Materials", GI
/// 2004; energy form of McAdams et al. 2011): with R the rotation of F = R S,
/// Ψ = μ ‖F − R‖² + ½ λ tr²(RᵀF − I), P = 2μ(F − R) + λ tr(RᵀF − I) R. R comes from
/// extract_rotation(), a proper rotation also for inverted elements. The stiffness is the
/// usual frozen-rotation tangent R K₀ Rᵀ: exact at rigidly rotated rest shapes, an
/// approximation (omitting ∂R/∂x) elsewhere — sufficient for implicit Euler and Newton.
class CorotationalFem final : public TetFemModel {
 public:
  CorotationalFem(std::vector<Tet> tets, std::span<const Vec3> rest_positions_mm,
                  const ElasticMaterial& material);
  [[nodiscard]] std::string_view kind() const override { return "corotational_fem"; }

 protected:
  [[nodiscard]] double energy_density(std::size_t e, const Mat3& F) const override;
  [[nodiscard]] Mat3 first_piola(std::size_t e, const Mat3& F) const override;
  [[nodiscard]] Mat3 dP_dF(std::size_t e, const Mat3& F, const Mat3& dF) const override;
  void element_stiffness(std::size_t e, const Mat3& F, const std::array<Vec3, 4>& b,
                         std::span<Mat3, 16> out) const override;

 private:
  [[nodiscard]] Mat3 rotation(std::size_t e, const Mat3& F) const;
  /// Last rotation of an element and the F it was computed for (forces and stiffness at the
  /// same positions reuse it instead of extracting it again).
  struct CachedRotation {
    Mat3 F = Mat3::Constant(std::numeric_limits<double>::quiet_NaN());
    Mat3 R = Mat3::Identity();
  };
  mutable std::vector<Eigen::Quaterniond> m_rotation;   // warm start per element
  mutable std::vector<Eigen::Quaterniond> m_previous;   // the rotation before it
  mutable std::vector<CachedRotation> m_cached;
};

}  // namespace ido::sim
