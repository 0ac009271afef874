// SPDX-License-Identifier: Apache-2.0
#include "ido/sim/world.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/SparseCholesky>

#include "ido/core/error.h"
#include "ido/sim/fem_common.h"
#include "ido/sim/units.h"

namespace ido::sim {

// ---- ForceModel defaults -----------------------------------------------------------------

void ForceModel::stiffness_blocks(const Particles&, std::span<Mat3>, bool) const {}

void ForceModel::add_stiffness_to(const Particles& particles, std::span<const std::int32_t> slots,
                                  std::span<Mat3> values, bool threaded) const {
  std::vector<Mat3> blocks(slots.size());
  stiffness_blocks(particles, blocks, threaded);
  for (std::size_t k = 0; k < slots.size(); ++k)
    if (slots[k] >= 0) values[static_cast<std::size_t>(slots[k])] += blocks[k];
}

void ForceModel::add_stiffness_product(const Particles& particles, std::span<const Vec3> dx_mm,
                                       std::span<Vec3> out_n) const {
  const auto pattern = stiffness_pattern();
  std::vector<Mat3> blocks(pattern.size());
  stiffness_blocks(particles, blocks, false);
  for (std::size_t k = 0; k < pattern.size(); ++k)
    out_n[static_cast<std::size_t>(pattern[k].row)] +=
        blocks[k] * dx_mm[static_cast<std::size_t>(pattern[k].col)];
}

Eigen::SparseMatrix<double> ForceModel::stiffness_matrix(const Particles& particles) const {
  const auto pattern = stiffness_pattern();
  std::vector<Mat3> blocks(pattern.size());
  stiffness_blocks(particles, blocks, false);
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(9 * pattern.size());
  for (std::size_t k = 0; k < pattern.size(); ++k)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        triplets.emplace_back(3 * pattern[k].row + r, 3 * pattern[k].col + c, blocks[k](r, c));
  const auto n = static_cast<Eigen::Index>(3 * particles.size());
  Eigen::SparseMatrix<double> k(n, n);
  k.setFromTriplets(triplets.begin(), triplets.end());
  return k;
}

// ---- World -------------------------------------------------------------------------------

World::World() = default;
World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

std::int32_t World::add_tet_body(const geometry::TetMesh& mesh, double density_kg_m3) {
  if (mesh.vertices.empty() || mesh.tets.empty())
    throw InvalidInput("tetrahedral body: the mesh has no vertices or no tetrahedra");
  if (!(density_kg_m3 > 0.0) || !std::isfinite(density_kg_m3))
    throw InvalidInput("tetrahedral body: density must be positive");
  const double rho = density_kg_m3 * kKgPerM3ToKgPerMm3;
  std::vector<double> mass(mesh.vertices.size(), 0.0);
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    const auto& t = mesh.tets[e];
    for (auto i : t)
      if (i < 0 || static_cast<std::size_t>(i) >= mesh.vertices.size())
        throw InvalidInput("tetrahedral body: tetrahedron " + std::to_string(e) +
                           " has a vertex index out of range");
    const double vol = tet_signed_volume(mesh.vertices[static_cast<std::size_t>(t[0])],
                                         mesh.vertices[static_cast<std::size_t>(t[1])],
                                         mesh.vertices[static_cast<std::size_t>(t[2])],
                                         mesh.vertices[static_cast<std::size_t>(t[3])]);
    if (!(vol > 0.0))
      throw InvalidInput("tetrahedral body: tetrahedron " + std::to_string(e) +
                         (vol < 0.0 ? " is inverted (negative volume)" : " is degenerate (zero volume)"));
    for (auto i : t) mass[static_cast<std::size_t>(i)] += 0.25 * rho * vol;
  }
  // Every check before the first particle is added: a refused body leaves the world as it was.
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    if (!(mass[i] > 0.0))
      throw InvalidInput("tetrahedral body: vertex " + std::to_string(i) +
                         " belongs to no tetrahedron");
  const auto first = static_cast<std::int32_t>(m_particles.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) m_particles.add(mesh.vertices[i], mass[i]);
  return first;
}

ForceModel& World::add_model(std::unique_ptr<ForceModel> model) {
  if (!model) throw InvalidInput("World::add_model: null model");
  m_models.push_back(std::move(model));
  ++m_model_revision;
  return *m_models.back();
}

Integrator& World::scheme(const std::string& name) {
  const std::uint64_t revision = m_registry.revision(name);
  auto it = m_schemes.find(name);
  if (it != m_schemes.end() && it->second.revision == revision && revision != 0) return *it->second.instance;
  auto instance = m_registry.create(name);   // throws if unknown
  auto& slot = m_schemes[name];
  slot.instance = std::move(instance);
  slot.revision = revision;
  return *slot.instance;
}

void World::throw_scheme_type(const std::string& name) {
  throw InvalidInput("integrator '" + name + "' is not of the type asked for (it was registered as another scheme)");
}

void World::set_integrator(const std::string& name) {
  (void)scheme(name);   // throws if unknown; makes the instance now (not inside a step)
  m_integrator = name;
}

void World::compute_forces() {
  auto& f = m_particles.forces();
  const std::size_t n = m_particles.size();
  m_particles.clear_forces();
  for (const auto& m : m_models) m->add_forces(m_particles, f, m_threaded);
  const auto& mass = m_particles.masses();
  const auto& v = m_particles.velocities();
  const Vec3 g = m_external.gravity_mm_s2;
  const double alpha = m_external.damping.mass_per_s;
  for (std::size_t i = 0; i < n; ++i)
    f[i] += kKgMmPerS2ToNewton * mass[i] * (g - alpha * v[i]);
  if (m_external.damping.stiffness_s != 0.0) {
    std::vector<Vec3> kv(n, Vec3::Zero());
    for (const auto& m : m_models)
      if (m->has_stiffness()) m->add_stiffness_product(m_particles, v, kv);
    for (std::size_t i = 0; i < n; ++i) f[i] -= m_external.damping.stiffness_s * kv[i];
  }
  for (const auto& load : m_external.point_loads) {
    if (load.particle < 0 || static_cast<std::size_t>(load.particle) >= n)
      throw InvalidInput("point load on particle " + std::to_string(load.particle) +
                         ": index out of range");
    f[static_cast<std::size_t>(load.particle)] += load.force_n;
  }
  for (std::size_t i = 0; i < n; ++i)
    if (m_particles.fixed(i)) f[i].setZero();
  ++m_stats.force_evaluations;
}

std::vector<Vec3> World::accelerations() const {
  const auto& f = m_particles.forces();
  const auto& inv = m_particles.inverse_masses();
  std::vector<Vec3> a(m_particles.size());
  for (std::size_t i = 0; i < a.size(); ++i) a[i] = f[i] * (inv[i] / kKgMmPerS2ToNewton);
  return a;
}

void World::step(double dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s))
    throw InvalidInput("World::step: dt must be positive and finite, got " + std::to_string(dt_s));
  m_stats = StepStats{};
  scheme(m_integrator).step(*this, dt_s);
  auto& x = m_particles.positions();
  auto& v = m_particles.velocities();
  for (const auto& plane : m_external.planes) {
    const Vec3 nrm = plane.normal.normalized();
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (m_particles.fixed(i)) continue;
      const double depth = (x[i] - plane.point_mm).dot(nrm);
      if (depth < 0.0) {
        x[i] -= depth * nrm;
        const double vn = v[i].dot(nrm);
        if (vn < 0.0) v[i] -= vn * nrm;
      }
    }
  }
  m_time_s += dt_s;
  ++m_steps;
}

// ---- static equilibrium ------------------------------------------------------------------

StaticSolveResult solve_static(World& world, const StaticSolveOptions& options) {
  auto& p = world.particles();
  const std::size_t n = p.size();
  for (auto& v : p.velocities()) v.setZero();
  // Reduced numbering: free particles only.
  std::vector<Eigen::Index> dof(n, -1);
  Eigen::Index nfree = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (!p.fixed(i)) dof[i] = nfree++;
  StaticSolveResult result;
  if (nfree == 0) {
    result.converged = true;
    return result;
  }
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  for (int it = 0; it <= options.max_newton_iterations; ++it) {
    world.compute_forces();
    const auto& f = p.forces();
    double max_f = 0.0;
    for (std::size_t i = 0; i < n; ++i)
      if (!p.fixed(i)) max_f = std::max(max_f, f[i].norm());
    result.max_residual_force_n = max_f;
    result.newton_iterations = it;
    if (max_f <= options.force_tolerance_n) {
      result.converged = true;
      return result;
    }
    if (it == options.max_newton_iterations) break;
    std::vector<Eigen::Triplet<double>> triplets;
    for (const auto& m : world.models()) {
      if (!m->has_stiffness()) continue;
      const auto pattern = m->stiffness_pattern();
      std::vector<Mat3> blocks(pattern.size());
      m->stiffness_blocks(p, blocks, world.threaded());
      for (std::size_t k = 0; k < pattern.size(); ++k) {
        const auto r = dof[static_cast<std::size_t>(pattern[k].row)];
        const auto c = dof[static_cast<std::size_t>(pattern[k].col)];
        if (r < 0 || c < 0) continue;
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) triplets.emplace_back(3 * r + a, 3 * c + b, blocks[k](a, b));
      }
    }
    Eigen::SparseMatrix<double> k(3 * nfree, 3 * nfree);
    k.setFromTriplets(triplets.begin(), triplets.end());
    Eigen::VectorXd rhs(3 * nfree);
    for (std::size_t i = 0; i < n; ++i)
      if (dof[i] >= 0) rhs.segment<3>(3 * dof[i]) = f[i];
    if (it == 0) solver.analyzePattern(k);
    solver.factorize(k);
    if (solver.info() != Eigen::Success)
      throw InvalidInput("static solve: the stiffness matrix is singular (is anything fixed?)");
    const Eigen::VectorXd dx = solver.solve(rhs);
    auto& x = p.positions();
    for (std::size_t i = 0; i < n; ++i)
      if (dof[i] >= 0) x[i] += dx.segment<3>(3 * dof[i]);
  }
  return result;
}

}  // namespace ido::sim
