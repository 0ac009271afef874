// SPDX-License-Identifier: Apache-2.0
#include "ido/sim/particles.h"

#include "ido/core/error.h"

namespace ido::sim {

std::size_t Particles::add(const Vec3& position_mm, double mass_kg, const Vec3& velocity_mm_s) {
  if (!(mass_kg > 0.0)) throw InvalidInput("particle mass must be positive");
  m_position.push_back(position_mm);
  m_velocity.push_back(velocity_mm_s);
  m_force.push_back(Vec3::Zero());
  m_mass.push_back(mass_kg);
  m_inv_mass.push_back(1.0 / mass_kg);
  m_fixed.push_back(0);
  return m_position.size() - 1;
}

void Particles::resize(std::size_t n) {
  m_position.resize(n, Vec3::Zero());
  m_velocity.resize(n, Vec3::Zero());
  m_force.resize(n, Vec3::Zero());
  m_mass.resize(n, 1.0);
  m_inv_mass.resize(n, 1.0);
  m_fixed.resize(n, 0);
}

void Particles::set_mass(std::size_t i, double mass_kg) {
  if (!(mass_kg > 0.0)) throw InvalidInput("particle mass must be positive");
  m_mass[i] = mass_kg;
  m_inv_mass[i] = m_fixed[i] ? 0.0 : 1.0 / mass_kg;
}

void Particles::set_fixed(std::size_t i, bool fixed) {
  m_fixed[i] = fixed ? 1 : 0;
  m_inv_mass[i] = fixed ? 0.0 : 1.0 / m_mass[i];
  if (fixed) m_velocity[i] = Vec3::Zero();
}

void Particles::clear_forces() {
  for (auto& f : m_force) f.setZero();
}

}  // namespace ido::sim
