// SPDX-License-Identifier: Apache-2.0
#include "ido/sim/shape_matching.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

#include <Eigen/LU>
#include <fmt/format.h>

#include "gather.h"
#include "ido/core/error.h"
#include "ido/core/parallel.h"
#include "ido/sim/fem_common.h"
#include "ido/sim/units.h"

namespace ido::sim {

namespace {
using Vec9 = Eigen::Matrix<double, 9, 1>;
Vec9 quadratic_terms(const Vec3& q) {
  Vec9 t;
  t << q.x(), q.y(), q.z(), q.x() * q.x(), q.y() * q.y(), q.z() * q.z(), q.x() * q.y(),
      q.y() * q.z(), q.z() * q.x();
  return t;
}
}  // namespace

ShapeMatching::ShapeMatching(const Particles& particles,
                             std::vector<std::vector<std::int32_t>> clusters,
                             const ShapeMatchingOptions& options)
    : m_clusters(std::move(clusters)), m_options(options) {
  if (m_clusters.empty()) throw InvalidInput("shape matching: no clusters");
  if (!(options.beta >= 0.0 && options.beta <= 1.0))
    throw InvalidInput("shape matching: beta must be in [0, 1]");
  if (!(options.stiffness_per_s2 >= 0.0) || !std::isfinite(options.stiffness_per_s2))
    throw InvalidInput("shape matching: stiffness must be non-negative");
  const auto& x = particles.positions();
  const auto& m = particles.masses();
  std::vector<std::int32_t> targets;
  std::int32_t max_index = 0;
  for (std::size_t c = 0; c < m_clusters.size(); ++c) {
    const auto& cl = m_clusters[c];
    const std::string where = "shape matching: cluster " + std::to_string(c) + ": ";
    if (cl.empty()) throw InvalidInput(where + "empty");
    m_slot_offset.push_back(static_cast<std::int32_t>(targets.size()));
    double mass = 0.0;
    Vec3 centre = Vec3::Zero();
    for (auto i : cl) {
      if (i < 0 || static_cast<std::size_t>(i) >= particles.size())
        throw InvalidInput(where + "particle index out of range");
      mass += m[static_cast<std::size_t>(i)];
      centre += m[static_cast<std::size_t>(i)] * x[static_cast<std::size_t>(i)];
      targets.push_back(i);
      max_index = std::max(max_index, i);
    }
    centre /= mass;
    m_rest_centre.push_back(centre);
    std::vector<Vec3> q;
    Mat3 aqq = Mat3::Zero();
    Eigen::Matrix<double, 9, 9> aqq9 = Eigen::Matrix<double, 9, 9>::Zero();
    for (auto i : cl) {
      const Vec3 qi = x[static_cast<std::size_t>(i)] - centre;
      q.push_back(qi);
      const double mi = m[static_cast<std::size_t>(i)];
      aqq += mi * qi * qi.transpose();
      if (options.mode == ShapeMatchingMode::Quadratic) {
        const Vec9 t = quadratic_terms(qi);
        aqq9 += mi * t * t.transpose();
      }
    }
    m_q.push_back(std::move(q));
    if (options.mode == ShapeMatchingMode::Linear) {
      Eigen::FullPivLU<Mat3> lu(aqq);
      lu.setThreshold(1e-10);
      if (cl.size() < 4 || !lu.isInvertible())
        throw InvalidInput(where + "needs at least 4 non-coplanar particles for linear matching");
      m_aqq_inv.push_back(aqq.inverse());
    } else if (options.mode == ShapeMatchingMode::Quadratic) {
      Eigen::FullPivLU<Eigen::Matrix<double, 9, 9>> lu(aqq9);
      lu.setThreshold(1e-10);
      if (!lu.isInvertible())
        throw InvalidInput(where + "too few or too regularly placed particles for quadratic matching (needs ≥ 10 spread in 3D)");
      m_aqq9_inv.push_back(lu.inverse());
    }
  }
  m_slot_offset.push_back(static_cast<std::int32_t>(targets.size()));
  m_rotation.assign(m_clusters.size(), Eigen::Quaterniond::Identity());
  detail::build_gather(targets, static_cast<std::size_t>(max_index + 1), m_offsets, m_sources);
}

void ShapeMatching::goals(const Particles& particles, std::size_t c, std::span<Vec3> out) const {
  const auto& x = particles.positions();
  const auto& m = particles.masses();
  const auto& cl = m_clusters[c];
  const auto& q = m_q[c];
  double mass = 0.0;
  Vec3 centre = Vec3::Zero();
  for (auto i : cl) {
    mass += m[static_cast<std::size_t>(i)];
    centre += m[static_cast<std::size_t>(i)] * x[static_cast<std::size_t>(i)];
  }
  centre /= mass;
  Mat3 apq = Mat3::Zero();
  for (std::size_t k = 0; k < cl.size(); ++k)
    apq += m[static_cast<std::size_t>(cl[k])] * (x[static_cast<std::size_t>(cl[k])] - centre) * q[k].transpose();
  const Mat3 r = extract_rotation(apq, m_rotation[c]);
  const double beta = m_options.beta;
  switch (m_options.mode) {
    case ShapeMatchingMode::Rigid:
      for (std::size_t k = 0; k < cl.size(); ++k) out[k] = r * q[k] + centre;
      break;
    case ShapeMatchingMode::Linear: {
      Mat3 a = apq * m_aqq_inv[c];
      const double det = a.determinant();
      if (m_options.preserve_volume) a = det > 0.0 ? Mat3(a / std::cbrt(det)) : r;
      const Mat3 t = beta * a + (1.0 - beta) * r;
      for (std::size_t k = 0; k < cl.size(); ++k) out[k] = t * q[k] + centre;
      break;
    }
    case ShapeMatchingMode::Quadratic: {
      Eigen::Matrix<double, 3, 9> apq9 = Eigen::Matrix<double, 3, 9>::Zero();
      for (std::size_t k = 0; k < cl.size(); ++k)
        apq9 += m[static_cast<std::size_t>(cl[k])] * (x[static_cast<std::size_t>(cl[k])] - centre) *
                quadratic_terms(q[k]).transpose();
      Eigen::Matrix<double, 3, 9> rt = Eigen::Matrix<double, 3, 9>::Zero();
      rt.leftCols<3>() = r;
      const Eigen::Matrix<double, 3, 9> t = beta * (apq9 * m_aqq9_inv[c]) + (1.0 - beta) * rt;
      for (std::size_t k = 0; k < cl.size(); ++k) out[k] = t * quadratic_terms(q[k]) + centre;
      break;
    }
  }
}

std::vector<Vec3> ShapeMatching::goal_positions(const Particles& particles) const {
  std::vector<Vec3> g(static_cast<std::size_t>(m_slot_offset.back()));
  for (std::size_t c = 0; c < m_clusters.size(); ++c)
    goals(particles, c, std::span<Vec3>(g.data() + m_slot_offset[c], m_clusters[c].size()));
  return g;
}

void ShapeMatching::add_forces(const Particles& particles, std::span<Vec3> forces_n,
                               bool threaded) const {
  const auto& x = particles.positions();
  const auto& m = particles.masses();
  std::vector<Vec3> slots(static_cast<std::size_t>(m_slot_offset.back()));
  const double k = m_options.stiffness_per_s2 * kKgMmPerS2ToNewton;
  parallel_for(
      m_clusters.size(),
      [&](std::size_t c) {
        std::span<Vec3> s(slots.data() + m_slot_offset[c], m_clusters[c].size());
        goals(particles, c, s);
        for (std::size_t j = 0; j < s.size(); ++j) {
          const auto i = static_cast<std::size_t>(m_clusters[c][j]);
          s[j] = k * m[i] * (s[j] - x[i]);
        }
      },
      threaded, 16);
  detail::gather_add(m_offsets, m_sources, slots, forces_n, threaded);
}

double ShapeMatching::energy(const Particles& particles) const {
  const auto g = goal_positions(particles);
  const auto& x = particles.positions();
  const auto& m = particles.masses();
  double e = 0.0;
  std::size_t s = 0;
  for (const auto& cl : m_clusters)
    for (auto i : cl) {
      e += 0.5 * m_options.stiffness_per_s2 * m[static_cast<std::size_t>(i)] *
           (g[s++] - x[static_cast<std::size_t>(i)]).squaredNorm();
    }
  return e * kKgMmPerS2ToNewton;
}

void ShapeMatching::set_stiffness(double stiffness_per_s2) {
  if (!(stiffness_per_s2 >= 0.0) || !std::isfinite(stiffness_per_s2))
    throw InvalidInput(fmt::format("shape_matching: stiffness_per_s2 must be >= 0 and finite, got {}", stiffness_per_s2));
  m_options.stiffness_per_s2 = stiffness_per_s2;
}

void ShapeMatching::set_beta(double beta) {
  if (!(beta >= 0.0 && beta <= 1.0)) throw InvalidInput(fmt::format("shape_matching: beta must be in [0, 1], got {}", beta));
  m_options.beta = beta;
}

std::vector<std::vector<std::int32_t>> grid_clusters(std::span<const Vec3> positions_mm,
                                                     double cell_mm) {
  if (!(cell_mm > 0.0)) throw InvalidInput("grid clusters: cell size must be positive");
  auto key = [](std::int64_t i, std::int64_t j, std::int64_t k) {
    return (i * 73856093) ^ (j * 19349663) ^ (k * 83492791);
  };
  struct Cell {
    std::int64_t i, j, k;
    std::vector<std::int32_t> members;
  };
  std::unordered_map<std::int64_t, std::vector<Cell>> cells;
  std::vector<std::array<std::int64_t, 3>> order;
  for (std::size_t p = 0; p < positions_mm.size(); ++p) {
    const auto i = static_cast<std::int64_t>(std::floor(positions_mm[p].x() / cell_mm));
    const auto j = static_cast<std::int64_t>(std::floor(positions_mm[p].y() / cell_mm));
    const auto k = static_cast<std::int64_t>(std::floor(positions_mm[p].z() / cell_mm));
    auto& bucket = cells[key(i, j, k)];
    auto it = std::find_if(bucket.begin(), bucket.end(),
                           [&](const Cell& c) { return c.i == i && c.j == j && c.k == k; });
    if (it == bucket.end()) {
      bucket.push_back({i, j, k, {}});
      order.push_back({i, j, k});
      it = bucket.end() - 1;
    }
    it->members.push_back(static_cast<std::int32_t>(p));
  }
  std::sort(order.begin(), order.end());
  std::vector<std::vector<std::int32_t>> out;
  for (const auto& [i, j, k] : order) {
    const Vec3 centre = cell_mm * Vec3(static_cast<double>(i) + 0.5, static_cast<double>(j) + 0.5,
                                       static_cast<double>(k) + 0.5);
    std::vector<std::int32_t> members;
    for (std::int64_t dk = -2; dk <= 2; ++dk)
      for (std::int64_t dj = -2; dj <= 2; ++dj)
        for (std::int64_t di = -2; di <= 2; ++di) {
          const auto it = cells.find(key(i + di, j + dj, k + dk));
          if (it == cells.end()) continue;
          for (const auto& c : it->second) {
            if (c.i != i + di || c.j != j + dj || c.k != k + dk) continue;
            for (auto p : c.members)
              if ((positions_mm[static_cast<std::size_t>(p)] - centre).cwiseAbs().maxCoeff() <= 1.5 * cell_mm)
                members.push_back(p);
          }
        }
    std::sort(members.begin(), members.end());
    if (members.size() >= 4) out.push_back(std::move(members));
  }
  return out;
}

}  // namespace ido::sim
