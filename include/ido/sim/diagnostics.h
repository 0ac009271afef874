// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <string>
#include <vector>

#include "ido/core/math.h"
#include "ido/sim/particles.h"

namespace ido::sim {

class World;

/// Energies of a world, millijoules (N·mm).
struct EnergyReport {
  double kinetic_mj = 0.0;          ///< ½ Σ m v² (converted, units.h)
  double gravitational_mj = 0.0;    ///< −Σ m g·x, zero at the origin
  std::vector<double> elastic_mj;   ///< one per model, in World::models() order
  std::vector<std::string> model_kinds;
  [[nodiscard]] double elastic_total_mj() const;
  [[nodiscard]] double total_mj() const { return kinetic_mj + gravitational_mj + elastic_total_mj(); }
};

/// Kinetic, gravitational and per-model elastic energy at the world's current state.
[[nodiscard]] EnergyReport energies(const World& world);

/// Linear and angular momentum of the particles.
struct Momentum {
  Vec3 linear_kg_mm_s = Vec3::Zero();     ///< Σ m v
  Vec3 angular_kg_mm2_s = Vec3::Zero();   ///< Σ (x − origin) × m v
};
/// Momentum about @p origin_mm (fixed particles included: they are at rest).
[[nodiscard]] Momentum momentum(const Particles& particles, const Vec3& origin_mm = Vec3::Zero());

}  // namespace ido::sim
