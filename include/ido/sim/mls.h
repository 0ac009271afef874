// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <vector>

#include "ido/core/math.h"
#include "ido/sim/fem_common.h"
#include "ido/sim/force_model.h"

namespace ido::sim {

struct MlsOptions {
  double support_radius_mm = 2.0;      ///< h: neighbours within h, kernel support
  ElasticMaterial material;
  double volume_stiffness_pa = 0.0;    ///< k_v of the volume term ½ k_v (det F − 1)²
};

/// Point-based elasticity after Müller, Keiser, Nealen, Pauly, Gross & Alexa, "Point Based
/// Animation of Elastic, Plastic and Melting Objects" (SCA 2004). Each particle (phyxel) i
/// has the neighbours j within h at rest, weights w_ij = W(‖X_j − X_i‖) with the poly6
/// kernel (h² − r²)³, the moment matrix A_i = Σ_j w_ij X_ij X_ijᵀ, and the MLS gradient
/// ∇u_i = (Σ_j w_ij (u_j − u_i) X_ijᵀ) A_i⁻¹ (exact for linear fields). With F = I + ∇u,
/// Green strain E, St Venant–Kirchhoff stress S = λ tr(E) I + 2μE, the energy is
/// U = Σ_i v_i (μ E:E + ½ λ tr²E + ½ k_v (det F − 1)²); forces are its exact negative
/// gradient. v_i = m_i / ρ_i, ρ_i = Σ_j m_j W_ij (including i). No stiffness.
class MlsElasticity final : public ForceModel {
 public:
  /// Phyxels are the listed particles (rest = current positions). @throws ido::InvalidInput
  /// for bad options or a particle whose moment matrix is singular (too few or coplanar
  /// neighbours: increase h).
  MlsElasticity(const Particles& particles, std::vector<std::int32_t> phyxels,
                const MlsOptions& options);

  [[nodiscard]] std::string_view kind() const override { return "mls_elasticity"; }
  void add_forces(const Particles& particles, std::span<Vec3> forces_n,
                  bool threaded) const override;
  [[nodiscard]] double energy(const Particles& particles) const override;
  /// Displacement gradient ∇u per phyxel (dimensionless).
  [[nodiscard]] std::vector<Mat3> displacement_gradients(const Particles& particles) const;
  /// Green strain ½(∇u + ∇uᵀ + ∇uᵀ∇u) per phyxel.
  [[nodiscard]] std::vector<Mat3> green_strains(const Particles& particles) const;
  [[nodiscard]] const MlsOptions& options() const noexcept { return m_options; }
  /// Changes the material (E, ν) between steps. @throws ido::InvalidInput naming
  /// youngs_modulus_pa or poisson_ratio when out of range (check_material); unchanged then.
  void set_material(const ElasticMaterial& material);
  /// Changes the volume term's k_v (Pa) between steps. @throws ido::InvalidInput naming
  /// volume_stiffness_pa unless ≥ 0 and finite.
  void set_volume_stiffness(double volume_stiffness_pa);
  [[nodiscard]] std::size_t neighbour_count(std::size_t i) const {
    return static_cast<std::size_t>(m_nbr_offset[i + 1] - m_nbr_offset[i]);
  }

 private:
  [[nodiscard]] Mat3 gradient(const Particles& particles, std::size_t i) const;
  std::vector<std::int32_t> m_phyxels;
  MlsOptions m_options;
  Lame m_lame;
  double m_kv = 0.0;                        // N/mm²
  std::vector<Vec3> m_rest;                 // rest positions of phyxels
  std::vector<double> m_volume;             // mm³
  std::vector<std::int32_t> m_nbr_offset;   // CSR over phyxels
  std::vector<std::int32_t> m_nbr;          // neighbour phyxel index
  std::vector<Vec3> m_d;                    // A⁻¹ X_ij w_ij per neighbour slot
  std::vector<std::int32_t> m_offsets, m_sources;   // gather per phyxel
};

}  // namespace ido::sim
