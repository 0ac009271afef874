// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "ido/core/math.h"

namespace ido::sim {

/// The particles of a simulated body, as a structure of arrays (mm, mm/s, kg, N).
/// A fixed particle keeps its position and has inverse mass 0. The set can grow (the
/// balloon adds particles when it refines); indices of existing particles never change
/// except through remove_swap-style operations documented where they are offered.
class Particles {
 public:
  Particles() = default;

  /// Appends a particle and returns its index. @p mass_kg must be positive.
  std::size_t add(const Vec3& position_mm, double mass_kg, const Vec3& velocity_mm_s = Vec3::Zero());
  /// Resizes to @p n particles; new ones are at the origin, at rest, with mass 1 kg.
  void resize(std::size_t n);
  [[nodiscard]] std::size_t size() const noexcept { return m_position.size(); }

  [[nodiscard]] std::vector<Vec3>& positions() noexcept { return m_position; }
  [[nodiscard]] const std::vector<Vec3>& positions() const noexcept { return m_position; }
  [[nodiscard]] std::vector<Vec3>& velocities() noexcept { return m_velocity; }
  [[nodiscard]] const std::vector<Vec3>& velocities() const noexcept { return m_velocity; }
  [[nodiscard]] std::vector<Vec3>& forces() noexcept { return m_force; }
  [[nodiscard]] const std::vector<Vec3>& forces() const noexcept { return m_force; }
  [[nodiscard]] const std::vector<double>& masses() const noexcept { return m_mass; }
  /// 1 / mass, or 0 for fixed particles.
  [[nodiscard]] const std::vector<double>& inverse_masses() const noexcept { return m_inv_mass; }
  [[nodiscard]] bool fixed(std::size_t i) const noexcept { return m_fixed[i] != 0; }

  /// Sets a particle's mass (kg, > 0); keeps the inverse mass consistent with `fixed`.
  void set_mass(std::size_t i, double mass_kg);
  /// Fixes or frees a particle. A fixed particle's velocity is zeroed.
  void set_fixed(std::size_t i, bool fixed);
  /// Sets every force to zero.
  void clear_forces();

 private:
  std::vector<Vec3> m_position;
  std::vector<Vec3> m_velocity;
  std::vector<Vec3> m_force;
  std::vector<double> m_mass;
  std::vector<double> m_inv_mass;
  std::vector<std::uint8_t> m_fixed;
};

}  // namespace ido::sim
