// SPDX-License-Identifier: Apache-2.0
#include "ido/sim/diagnostics.h"

#include "ido/sim/units.h"
#include "ido/sim/world.h"

namespace ido::sim {

double EnergyReport::elastic_total_mj() const {
  double s = 0.0;
  for (double e : elastic_mj) s += e;
  return s;
}

EnergyReport energies(const World& world) {
  EnergyReport r;
  const auto& p = world.particles();
  const auto& x = p.positions();
  const auto& v = p.velocities();
  const auto& m = p.masses();
  const Vec3 g = world.external().gravity_mm_s2;
  for (std::size_t i = 0; i < p.size(); ++i) {
    r.kinetic_mj += 0.5 * m[i] * v[i].squaredNorm() * kKgMmPerS2ToNewton;
    r.gravitational_mj -= m[i] * g.dot(x[i]) * kKgMmPerS2ToNewton;
  }
  for (const auto& model : world.models()) {
    r.elastic_mj.push_back(model->energy(p));
    r.model_kinds.emplace_back(model->kind());
  }
  return r;
}

Momentum momentum(const Particles& particles, const Vec3& origin_mm) {
  Momentum out;
  const auto& x = particles.positions();
  const auto& v = particles.velocities();
  const auto& m = particles.masses();
  for (std::size_t i = 0; i < particles.size(); ++i) {
    const Vec3 pi = m[i] * v[i];
    out.linear_kg_mm_s += pi;
    out.angular_kg_mm2_s += (x[i] - origin_mm).cross(pi);
  }
  return out;
}

}  // namespace ido::sim
