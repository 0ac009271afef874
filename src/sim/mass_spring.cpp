// SPDX-License-Identifier: Apache-2.0
#include "ido/sim/mass_spring.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include <fmt/format.h>

#include "gather.h"
#include "ido/core/error.h"

namespace ido::sim {

MassSpring::MassSpring(std::vector<Spring> springs) : m_springs(std::move(springs)) {
  std::vector<std::int32_t> targets;
  targets.reserve(2 * m_springs.size());
  std::int32_t max_index = -1;
  for (std::size_t s = 0; s < m_springs.size(); ++s) {
    const auto& sp = m_springs[s];
    const std::string where = "spring " + std::to_string(s) + ": ";
    if (sp.a < 0 || sp.b < 0 || sp.a == sp.b)
      throw InvalidInput(where + "needs two different non-negative particle indices");
    if (!(sp.rest_length_mm > 0.0) || !std::isfinite(sp.rest_length_mm))
      throw InvalidInput(where + "rest length must be positive");
    if (!(sp.stiffness_n_per_mm >= 0.0) || !std::isfinite(sp.stiffness_n_per_mm))
      throw InvalidInput(where + "stiffness must be non-negative");
    if (!(sp.damping_n_s_per_mm >= 0.0) || !std::isfinite(sp.damping_n_s_per_mm))
      throw InvalidInput(where + "damping must be non-negative");
    targets.push_back(sp.a);
    targets.push_back(sp.b);
    max_index = std::max({max_index, sp.a, sp.b});
  }
  detail::build_gather(targets, static_cast<std::size_t>(max_index + 1), m_offsets, m_sources);
}

void MassSpring::set_stiffness(double stiffness_n_per_mm) {
  if (!(stiffness_n_per_mm >= 0.0) || !std::isfinite(stiffness_n_per_mm))
    throw InvalidInput(fmt::format("mass_spring: stiffness_n_per_mm must be >= 0 and finite, got {}", stiffness_n_per_mm));
  for (auto& sp : m_springs) sp.stiffness_n_per_mm = stiffness_n_per_mm;
}

void MassSpring::set_damping(double damping_n_s_per_mm) {
  if (!(damping_n_s_per_mm >= 0.0) || !std::isfinite(damping_n_s_per_mm))
    throw InvalidInput(fmt::format("mass_spring: damping_n_s_per_mm must be >= 0 and finite, got {}", damping_n_s_per_mm));
  for (auto& sp : m_springs) sp.damping_n_s_per_mm = damping_n_s_per_mm;
}

MassSpring MassSpring::from_tet_edges(const geometry::TetMesh& mesh, std::int32_t first_particle,
                                      double stiffness_n_per_mm, double damping_n_s_per_mm) {
  std::set<std::pair<std::int32_t, std::int32_t>> edges;
  for (const auto& t : mesh.tets)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) edges.insert({std::min(t[i], t[j]), std::max(t[i], t[j])});
  std::vector<Spring> springs;
  springs.reserve(edges.size());
  for (const auto& [a, b] : edges) {
    if (a < 0 || static_cast<std::size_t>(b) >= mesh.vertices.size())
      throw InvalidInput("mass-spring: tetrahedron index out of range");
    springs.push_back({a + first_particle, b + first_particle,
                       (mesh.vertices[static_cast<std::size_t>(a)] -
                        mesh.vertices[static_cast<std::size_t>(b)]).norm(),
                       stiffness_n_per_mm, damping_n_s_per_mm});
  }
  return MassSpring(std::move(springs));
}

void MassSpring::add_forces(const Particles& particles, std::span<Vec3> forces_n,
                            bool threaded) const {
  const auto& x = particles.positions();
  const auto& v = particles.velocities();
  std::vector<Vec3> slots(2 * m_springs.size());
  parallel_for(
      m_springs.size(),
      [&](std::size_t s) {
        const auto& sp = m_springs[s];
        const auto a = static_cast<std::size_t>(sp.a), b = static_cast<std::size_t>(sp.b);
        const Vec3 d = x[a] - x[b];
        const double l = d.norm();
        if (l <= 0.0) {
          slots[2 * s].setZero();
          slots[2 * s + 1].setZero();
          return;
        }
        const Vec3 n = d / l;
        const double mag = sp.stiffness_n_per_mm * (l - sp.rest_length_mm) +
                           sp.damping_n_s_per_mm * (v[a] - v[b]).dot(n);
        slots[2 * s] = -mag * n;
        slots[2 * s + 1] = mag * n;
      },
      threaded, 2048);
  detail::gather_add(m_offsets, m_sources, slots, forces_n, threaded);
}

double MassSpring::energy(const Particles& particles) const {
  const auto& x = particles.positions();
  double e = 0.0;
  for (const auto& sp : m_springs) {
    const double dl = (x[static_cast<std::size_t>(sp.a)] - x[static_cast<std::size_t>(sp.b)]).norm() -
                      sp.rest_length_mm;
    e += 0.5 * sp.stiffness_n_per_mm * dl * dl;
  }
  return e;
}

std::vector<BlockIndex> MassSpring::stiffness_pattern() const {
  std::vector<BlockIndex> p;
  p.reserve(4 * m_springs.size());
  for (const auto& s : m_springs) {
    p.push_back({s.a, s.a});
    p.push_back({s.a, s.b});
    p.push_back({s.b, s.a});
    p.push_back({s.b, s.b});
  }
  return p;
}

void MassSpring::stiffness_blocks(const Particles& particles, std::span<Mat3> blocks,
                                  bool threaded) const {
  const auto& x = particles.positions();
  parallel_for(
      m_springs.size(),
      [&](std::size_t s) {
        const auto& sp = m_springs[s];
        const Vec3 d = x[static_cast<std::size_t>(sp.a)] - x[static_cast<std::size_t>(sp.b)];
        const double l = d.norm();
        Mat3 k = Mat3::Zero();
        if (l > 0.0) {
          const Vec3 n = d / l;
          const Mat3 nn = n * n.transpose();
          k = sp.stiffness_n_per_mm * (nn + (1.0 - sp.rest_length_mm / l) * (Mat3::Identity() - nn));
        }
        blocks[4 * s] = k;
        blocks[4 * s + 1] = -k;
        blocks[4 * s + 2] = -k;
        blocks[4 * s + 3] = k;
      },
      threaded, 2048);
}

}  // namespace ido::sim
