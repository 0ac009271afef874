// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/sim/force_model.h"

namespace ido::sim {

/// Isotropic elastic material. Young's modulus is in pascals (N/m²); internally the FEM
/// models work in N/mm² (1 Pa = 1e-6 N/mm², units.h).
struct ElasticMaterial {
  double youngs_modulus_pa = 1e5;   ///< E > 0
  double poisson_ratio = 0.3;       ///< −1 < ν < 0.5
};

/// Lamé parameters in N/mm².
struct Lame {
  double mu = 0.0;
  double lambda = 0.0;
};

/// μ = E / (2(1+ν)), λ = E ν / ((1+ν)(1−2ν)), converted to N/mm².
/// @throws ido::InvalidInput for E ≤ 0 or ν outside (−1, 0.5).
[[nodiscard]] Lame lame_parameters(const ElasticMaterial& material);

/// @p material checked parameter by parameter: @throws ido::InvalidInput "<where>:
/// youngs_modulus_pa must be > 0 and finite, got …" or "<where>: poisson_ratio must be in
/// (-1, 0.5), got …".
void check_material(const ElasticMaterial& material, std::string_view where);

/// Von Mises equivalent stress of a symmetric stress tensor (same unit as @p sigma).
[[nodiscard]] double von_mises(const Mat3& sigma);

/// Signed volume (mm³) of tetrahedron (a, b, c, d): (b−a)·((c−a)×(d−a)) / 6.
[[nodiscard]] double tet_signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Rotation of the polar decomposition F = R S (the rotation maximising tr(RᵀF)), started
/// from @p q (updated in place with the result: warm start). Newton steps on tr(RᵀF) near
/// the solution (quadratic convergence: two or three iterations from a previous time step's
/// rotation), the iterative method of Müller, Bender, Chentanez & Macklin, "A Robust Method
/// to Extract the Rotational Part of Deformations" (MIG 2016) elsewhere. Always a proper
/// rotation, also for inverted (det F < 0) or degenerate F.
[[nodiscard]] Mat3 extract_rotation(const Mat3& F, Eigen::Quaterniond& q, int max_iterations = 50);

/// Common part of the tetrahedral FEM models: linear tetrahedra, deformation gradient
/// F = D_s D_m⁻¹ (Sifakis & Barbič, "FEM Simulation of 3D Deformable Solids", SIGGRAPH 2012
/// course), forces f = −V P(F) D_m⁻ᵀ, energy V Ψ(F). A concrete model gives Ψ, P and the
/// stiffness of one element.
class TetFemModel : public ForceModel {
 public:
  /// @p tets index particles; rest shape from @p rest_positions_mm (indexed like particles).
  /// @throws ido::InvalidInput for bad indices, inverted or degenerate rest tetrahedra
  /// (naming the element) or a bad material.
  TetFemModel(std::vector<Tet> tets, std::span<const Vec3> rest_positions_mm,
              const ElasticMaterial& material);

  void add_forces(const Particles& particles, std::span<Vec3> forces_n,
                  bool threaded) const override;
  [[nodiscard]] double energy(const Particles& particles) const override;
  [[nodiscard]] std::vector<BlockIndex> stiffness_pattern() const override;
  void stiffness_blocks(const Particles& particles, std::span<Mat3> blocks,
                        bool threaded) const override;
  void add_stiffness_to(const Particles& particles, std::span<const std::int32_t> slots,
                        std::span<Mat3> values, bool threaded) const override;
  [[nodiscard]] std::optional<ElementFields> element_fields(const Particles&) const override;

  /// Deformation gradient of each element at the current positions.
  [[nodiscard]] std::vector<Mat3> deformation_gradients(const Particles& particles) const;
  [[nodiscard]] const std::vector<Tet>& tets() const noexcept { return m_tets; }
  [[nodiscard]] const Lame& lame() const noexcept { return m_lame; }
  /// The material the model computes with.
  [[nodiscard]] const ElasticMaterial& material() const noexcept { return m_material; }
  /// Changes the material between steps (the rest shape stays). @throws ido::InvalidInput
  /// naming youngs_modulus_pa (must be > 0 and finite) or poisson_ratio (must be in
  /// (−1, 0.5)); the model is unchanged then.
  void set_material(const ElasticMaterial& material);
  /// Changes Young's modulus E (Pa), keeping ν. @throws as set_material.
  void set_youngs_modulus(double youngs_modulus_pa);
  /// Changes Poisson's ratio ν, keeping E. @throws as set_material.
  void set_poisson_ratio(double poisson_ratio);
  [[nodiscard]] double rest_volume_mm3(std::size_t e) const { return m_volume[e]; }
  /// When on, stiffness_blocks() returns each element's tangent projected onto the positive
  /// semi-definite cone (negative eigenvalues of the 12×12 element matrix clamped to 0, as in
  /// Teran, Sifakis, Irving & Fedkiw, SCA 2005), so implicit solves stay well posed for
  /// energies whose Hessian is indefinite under compression. Off: the exact tangent.
  void set_definite_stiffness(bool on) noexcept { m_definite = on; }
  [[nodiscard]] bool definite_stiffness() const noexcept { return m_definite; }

 protected:
  /// Energy density Ψ(F) in N/mm² (= mJ/mm³) of element @p e.
  [[nodiscard]] virtual double energy_density(std::size_t e, const Mat3& F) const = 0;
  /// First Piola–Kirchhoff stress P(F) in N/mm².
  [[nodiscard]] virtual Mat3 first_piola(std::size_t e, const Mat3& F) const = 0;
  /// The 16 blocks K_ab (a, b = 0..3, row-major) of element @p e; @p b holds the gradients
  /// of the barycentric shape functions (F = Σ x_a b_aᵀ). The default differentiates
  /// P with dP_dF() for exact stiffness.
  virtual void element_stiffness(std::size_t e, const Mat3& F, const std::array<Vec3, 4>& b,
                                 std::span<Mat3, 16> out) const;
  /// Directional derivative of P at F along dF (N/mm²).
  [[nodiscard]] virtual Mat3 dP_dF(std::size_t e, const Mat3& F, const Mat3& dF) const = 0;
  /// Shape-function gradients of element e (1/mm).
  [[nodiscard]] std::array<Vec3, 4> gradients(std::size_t e) const;
  /// Called before a sweep over all elements at new positions (e.g. to refresh rotations).
  virtual void update_state(const Particles& particles, bool threaded) const;

  std::vector<Tet> m_tets;
  std::vector<Mat3> m_dm_inv;     ///< D_m⁻¹ per element, 1/mm
  std::vector<double> m_volume;   ///< rest volume per element, mm³
  ElasticMaterial m_material;
  Lame m_lame;
  bool m_definite = false;

 private:
  std::vector<std::int32_t> m_offsets;   // gather: per particle, element corner slots
  std::vector<std::int32_t> m_sources;
  mutable std::vector<Mat3> m_block_scratch;   // threaded add_stiffness_to: element blocks
  mutable std::vector<Vec3> m_force_scratch;   // add_forces: element corner forces
};

}  // namespace ido::sim
