// SPDX-License-Identifier: Apache-2.0
#include "ido/sim/mls.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "gather.h"
#include "ido/core/error.h"
#include "ido/core/parallel.h"
#include "ido/sim/units.h"

namespace ido::sim {

namespace {
/// Poly6 kernel (Müller, Charypar & Gross, SCA 2003): 315 / (64 π h⁹) (h² − r²)³, 1/mm³.
double poly6(double r2, double h) {
  if (r2 >= h * h) return 0.0;
  const double d = h * h - r2;
  return 315.0 / (64.0 * kPi * std::pow(h, 9)) * d * d * d;
}
Mat3 cofactor(const Mat3& F) {
  Mat3 c;
  c.col(0) = F.col(1).cross(F.col(2));
  c.col(1) = F.col(2).cross(F.col(0));
  c.col(2) = F.col(0).cross(F.col(1));
  return c;
}
}  // namespace

void MlsElasticity::set_material(const ElasticMaterial& material) {
  check_material(material, kind());
  m_lame = lame_parameters(material);
  m_options.material = material;
}

void MlsElasticity::set_volume_stiffness(double volume_stiffness_pa) {
  if (!(volume_stiffness_pa >= 0.0) || !std::isfinite(volume_stiffness_pa))
    throw InvalidInput(fmt::format("mls_elasticity: volume_stiffness_pa must be >= 0 and finite, got {}", volume_stiffness_pa));
  m_options.volume_stiffness_pa = volume_stiffness_pa;
  m_kv = volume_stiffness_pa * kPascalToNPerMm2;
}

MlsElasticity::MlsElasticity(const Particles& particles, std::vector<std::int32_t> phyxels,
                             const MlsOptions& options)
    : m_phyxels(std::move(phyxels)), m_options(options), m_lame(lame_parameters(options.material)) {
  const double h = options.support_radius_mm;
  if (!(h > 0.0) || !std::isfinite(h)) throw InvalidInput("MLS: support radius must be positive");
  if (!(options.volume_stiffness_pa >= 0.0)) throw InvalidInput("MLS: volume stiffness must be ≥ 0");
  if (m_phyxels.empty()) throw InvalidInput("MLS: no particles");
  m_kv = options.volume_stiffness_pa * kPascalToNPerMm2;
  const std::size_t n = m_phyxels.size();
  std::int32_t max_index = 0;
  for (auto p : m_phyxels) {
    if (p < 0 || static_cast<std::size_t>(p) >= particles.size())
      throw InvalidInput("MLS: particle index out of range");
    max_index = std::max(max_index, p);
    m_rest.push_back(particles.positions()[static_cast<std::size_t>(p)]);
  }
  // Neighbours within h through a uniform grid of cell h.
  auto cell_of = [&](const Vec3& x) {
    return std::array<std::int64_t, 3>{static_cast<std::int64_t>(std::floor(x.x() / h)),
                                       static_cast<std::int64_t>(std::floor(x.y() / h)),
                                       static_cast<std::int64_t>(std::floor(x.z() / h))};
  };
  auto key = [](std::int64_t i, std::int64_t j, std::int64_t k) {
    return (i * 73856093) ^ (j * 19349663) ^ (k * 83492791);
  };
  std::unordered_map<std::int64_t, std::vector<std::int32_t>> grid;
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = cell_of(m_rest[i]);
    grid[key(c[0], c[1], c[2])].push_back(static_cast<std::int32_t>(i));
  }
  m_nbr_offset.assign(1, 0);
  const auto& mass = particles.masses();
  std::vector<double> density(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = cell_of(m_rest[i]);
    std::vector<std::int32_t> nb;
    for (int dk = -1; dk <= 1; ++dk)
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          const auto it = grid.find(key(c[0] + di, c[1] + dj, c[2] + dk));
          if (it == grid.end()) continue;
          for (auto j : it->second)
            if (static_cast<std::size_t>(j) != i &&
                (m_rest[static_cast<std::size_t>(j)] - m_rest[i]).squaredNorm() < h * h)
              nb.push_back(j);
        }
    std::sort(nb.begin(), nb.end());
    nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
    Mat3 a = Mat3::Zero();
    density[i] = mass[static_cast<std::size_t>(m_phyxels[i])] * poly6(0.0, h);
    for (auto j : nb) {
      const Vec3 xij = m_rest[static_cast<std::size_t>(j)] - m_rest[i];
      const double w = poly6(xij.squaredNorm(), h);
      a += w * xij * xij.transpose();
      density[i] += mass[static_cast<std::size_t>(m_phyxels[static_cast<std::size_t>(j)])] * w;
    }
    Eigen::SelfAdjointEigenSolver<Mat3> eig(a, Eigen::EigenvaluesOnly);
    const double lmax = eig.eigenvalues().maxCoeff();
    if (nb.size() < 3 || !(eig.eigenvalues().minCoeff() > 1e-8 * lmax))
      throw InvalidInput("MLS: particle " + std::to_string(m_phyxels[i]) + " has " +
                         std::to_string(nb.size()) +
                         " neighbours within the support radius, too few or coplanar for a "
                         "moment matrix; increase support_radius_mm");
    const Mat3 ainv = a.inverse();
    for (auto j : nb) {
      const Vec3 xij = m_rest[static_cast<std::size_t>(j)] - m_rest[i];
      m_nbr.push_back(j);
      m_d.push_back(ainv * xij * poly6(xij.squaredNorm(), h));
    }
    m_nbr_offset.push_back(static_cast<std::int32_t>(m_nbr.size()));
  }
  m_volume.resize(n);
  for (std::size_t i = 0; i < n; ++i) m_volume[i] = mass[static_cast<std::size_t>(m_phyxels[i])] / density[i];
  // Slots: for phyxel i, one for itself then one per neighbour.
  std::vector<std::int32_t> targets;
  for (std::size_t i = 0; i < n; ++i) {
    targets.push_back(m_phyxels[i]);
    for (auto k = m_nbr_offset[i]; k < m_nbr_offset[i + 1]; ++k)
      targets.push_back(m_phyxels[static_cast<std::size_t>(m_nbr[static_cast<std::size_t>(k)])]);
  }
  detail::build_gather(targets, static_cast<std::size_t>(max_index + 1), m_offsets, m_sources);
}

Mat3 MlsElasticity::gradient(const Particles& particles, std::size_t i) const {
  const auto& x = particles.positions();
  const Vec3 ui = x[static_cast<std::size_t>(m_phyxels[i])] - m_rest[i];
  Mat3 g = Mat3::Zero();
  for (auto k = m_nbr_offset[i]; k < m_nbr_offset[i + 1]; ++k) {
    const auto j = static_cast<std::size_t>(m_nbr[static_cast<std::size_t>(k)]);
    const Vec3 uj = x[static_cast<std::size_t>(m_phyxels[j])] - m_rest[j];
    g += (uj - ui) * m_d[static_cast<std::size_t>(k)].transpose();
  }
  return g;
}

std::vector<Mat3> MlsElasticity::displacement_gradients(const Particles& particles) const {
  std::vector<Mat3> out(m_phyxels.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = gradient(particles, i);
  return out;
}

std::vector<Mat3> MlsElasticity::green_strains(const Particles& particles) const {
  std::vector<Mat3> out(m_phyxels.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const Mat3 g = gradient(particles, i);
    out[i] = 0.5 * (g + g.transpose() + g.transpose() * g);
  }
  return out;
}

void MlsElasticity::add_forces(const Particles& particles, std::span<Vec3> forces_n,
                               bool threaded) const {
  const std::size_t n = m_phyxels.size();
  std::vector<Vec3> slots(m_nbr.size() + n);
  parallel_for(
      n,
      [&](std::size_t i) {
        const Mat3 F = Mat3::Identity() + gradient(particles, i);
        const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
        const Mat3 S = m_lame.lambda * E.trace() * Mat3::Identity() + 2.0 * m_lame.mu * E;
        const Mat3 P = F * S + m_kv * (F.determinant() - 1.0) * cofactor(F);
        const std::size_t base = static_cast<std::size_t>(m_nbr_offset[i]) + i;
        Vec3 self = Vec3::Zero();
        for (auto k = m_nbr_offset[i]; k < m_nbr_offset[i + 1]; ++k) {
          const Vec3 f = -m_volume[i] * (P * m_d[static_cast<std::size_t>(k)]);
          slots[base + 1 + static_cast<std::size_t>(k - m_nbr_offset[i])] = f;
          self -= f;
        }
        slots[base] = self;
      },
      threaded, 256);
  detail::gather_add(m_offsets, m_sources, slots, forces_n, threaded);
}

double MlsElasticity::energy(const Particles& particles) const {
  std::vector<double> e(m_phyxels.size());
  for (std::size_t i = 0; i < e.size(); ++i) {
    const Mat3 F = Mat3::Identity() + gradient(particles, i);
    const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
    const double tr = E.trace(), dj = F.determinant() - 1.0;
    e[i] = m_volume[i] * (m_lame.mu * E.squaredNorm() + 0.5 * m_lame.lambda * tr * tr + 0.5 * m_kv * dj * dj);
  }
  return detail::ordered_sum(e);
}

}  // namespace ido::sim
