// SPDX-License-Identifier: Apache-2.0
#include "ido/sim/fem_common.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "gather.h"
#include "ido/core/error.h"
#include "ido/core/parallel.h"
#include "ido/sim/units.h"

namespace ido::sim {

Lame lame_parameters(const ElasticMaterial& m) {
  if (!(m.youngs_modulus_pa > 0.0) || !std::isfinite(m.youngs_modulus_pa))
    throw InvalidInput("material: Young's modulus must be positive, got " +
                       std::to_string(m.youngs_modulus_pa) + " Pa");
  if (!(m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5))
    throw InvalidInput("material: Poisson ratio must be in (-1, 0.5), got " +
                       std::to_string(m.poisson_ratio));
  const double e = m.youngs_modulus_pa * kPascalToNPerMm2, nu = m.poisson_ratio;
  return {e / (2.0 * (1.0 + nu)), e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))};
}

void check_material(const ElasticMaterial& m, std::string_view where) {
  if (!(m.youngs_modulus_pa > 0.0) || !std::isfinite(m.youngs_modulus_pa))
    throw InvalidInput(fmt::format("{}: youngs_modulus_pa must be > 0 and finite, got {}", where, m.youngs_modulus_pa));
  if (!(m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5))
    throw InvalidInput(fmt::format("{}: poisson_ratio must be in (-1, 0.5), got {}", where, m.poisson_ratio));
}

double von_mises(const Mat3& sigma) {
  const Mat3 sym = 0.5 * (sigma + sigma.transpose());
  const Mat3 s = sym - sym.trace() / 3.0 * Mat3::Identity();
  return std::sqrt(1.5 * s.cwiseProduct(s).sum());
}

double tet_signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

Mat3 extract_rotation(const Mat3& F, Eigen::Quaterniond& q, int max_iterations) {
  // Maximise f(R) = tr(RᵀF) over rotations (its maximiser is the polar rotation of F, and
  // for inverted F the rotation closest to F). Each iteration updates R ← R exp([ω]×) in the
  // body frame. With A = RᵀF and S = sym(A), f(R exp[ω]) = f(R) + ω·g − ½ ωᵀHω + O(ω³) with
  // g = (A₂₁−A₁₂, A₀₂−A₂₀, A₁₀−A₀₁) and H = tr(A) I − S (derived for this code by expanding
  // exp([ω]×) to second order).
  //  - Near the maximiser H is positive definite (its eigenvalues are the pairwise sums of
  //    S's eigenvalues), and the Newton step ω = H⁻¹g converges quadratically.
  //  - Elsewhere (H not positive definite, or a Newton step longer than 0.5 rad) the step
  //    is the one of Müller, Bender, Chentanez & Macklin, "A Robust Method to Extract the
  //    Rotational Part of Deformations" (MIG 2016, Algorithm 1): ω = g / |tr A|, which
  //    converges from any start but only linearly (factor ≈ 1/3 per iteration near a pure
  //    rotation, so ~20 iterations for 1e-12 rad — the reason for the Newton step).
  // Stops when the step is below 1e-12 rad, below 1e-8 rad and no longer shrinking
  // (round-off floor), or after a Newton step below 1e-7 rad (the remaining error is then
  // of the order of its square).
  // Inside the loop q is not renormalised (R is built from it in homogeneous form, exact for
  // any non-zero q), the Newton step is solved through the adjugate of H and the tests use
  // squared norms: one division for each, no square roots, on the iteration's critical path.
  auto rotation_of = [](const Eigen::Quaterniond& u) {
    const double w = u.w(), x = u.x(), y = u.y(), z = u.z();
    const double ww = w * w, xx = x * x, yy = y * y, zz = z * z;
    const double s = 1.0 / (ww + xx + yy + zz), s2 = 2.0 * s;
    Mat3 r;
    r(0, 0) = (ww + xx - yy - zz) * s;
    r(1, 1) = (ww - xx + yy - zz) * s;
    r(2, 2) = (ww - xx - yy + zz) * s;
    r(0, 1) = (x * y - w * z) * s2;
    r(1, 0) = (x * y + w * z) * s2;
    r(0, 2) = (x * z + w * y) * s2;
    r(2, 0) = (x * z - w * y) * s2;
    r(1, 2) = (y * z - w * x) * s2;
    r(2, 1) = (y * z + w * x) * s2;
    return r;
  };
  double previous2 = 1e300;
  Mat3 r = rotation_of(q);
  for (int it = 0; it < max_iterations; ++it) {
    const Mat3 a = r.transpose() * F;
    const Vec3 g(a(2, 1) - a(1, 2), a(0, 2) - a(2, 0), a(1, 0) - a(0, 1));
    const double tr = a.trace();
    // H = tr I − sym(A). Positive definite with all LDLᵀ pivots above the floor ⇔ the leading
    // minors m1 = h00, m2, m3 = det H satisfy m1 > floor, m2 > floor·m1, m3 > floor·m2
    // (the pivots are m1, m2/m1, m3/m2); then the Newton step ω = adj(H) g / det H.
    const double h00 = tr - a(0, 0), h11 = tr - a(1, 1), h22 = tr - a(2, 2);
    const double h10 = -0.5 * (a(1, 0) + a(0, 1)), h20 = -0.5 * (a(2, 0) + a(0, 2)),
                 h21 = -0.5 * (a(2, 1) + a(1, 2));
    const double pivot_floor = 1e-3 * std::abs(tr);
    Vec3 w;
    bool newton = false;
    const double c00 = h11 * h22 - h21 * h21, c01 = h20 * h21 - h10 * h22,
                 c02 = h10 * h21 - h11 * h20, c11 = h00 * h22 - h20 * h20,
                 c12 = h10 * h20 - h00 * h21, m2 = h00 * h11 - h10 * h10;
    const double det = h00 * c00 + h10 * c01 + h20 * c02;
    if (h00 > pivot_floor && m2 > pivot_floor * h00 && det > pivot_floor * m2) {
      const double inv = 1.0 / det;
      w.x() = (c00 * g.x() + c01 * g.y() + c02 * g.z()) * inv;
      w.y() = (c01 * g.x() + c11 * g.y() + c12 * g.z()) * inv;
      w.z() = (c02 * g.x() + c12 * g.y() + m2 * g.z()) * inv;
      newton = w.squaredNorm() < 0.25;
    }
    if (!newton) w = g * (1.0 / (std::abs(tr) + 1e-300));
    const double wn2 = w.squaredNorm();
    if (wn2 < 1e-24 || (wn2 < 1e-16 && wn2 >= previous2)) break;
    previous2 = wn2;
    if (newton) {
      // exp of a short step: the quaternion (1, ω/2) (rotation angle 2 atan(|ω|/2) =
      // |ω| + O(|ω|³), which keeps the quadratic convergence).
      q = q * Eigen::Quaterniond(1.0, 0.5 * w.x(), 0.5 * w.y(), 0.5 * w.z());
    } else {
      const double wn = std::sqrt(wn2);
      q.normalize();
      q = q * Eigen::Quaterniond(Eigen::AngleAxisd(wn, w / wn));
    }
    r = rotation_of(q);
    if (newton && wn2 < 1e-14) break;
  }
  q.normalize();
  return r;
}

TetFemModel::TetFemModel(std::vector<Tet> tets, std::span<const Vec3> rest_positions_mm,
                         const ElasticMaterial& material)
    : m_tets(std::move(tets)), m_material(material), m_lame(lame_parameters(material)) {
  if (m_tets.empty()) throw InvalidInput("FEM model: no tetrahedra");
  m_dm_inv.resize(m_tets.size());
  m_volume.resize(m_tets.size());
  std::vector<std::int32_t> targets;
  targets.reserve(4 * m_tets.size());
  std::int32_t max_index = 0;
  for (std::size_t e = 0; e < m_tets.size(); ++e) {
    const auto& t = m_tets[e];
    for (auto i : t) {
      if (i < 0 || static_cast<std::size_t>(i) >= rest_positions_mm.size())
        throw InvalidInput("FEM model: tetrahedron " + std::to_string(e) +
                           " has a particle index out of range");
      targets.push_back(i);
      max_index = std::max(max_index, i);
    }
    const Vec3& x0 = rest_positions_mm[static_cast<std::size_t>(t[0])];
    Mat3 dm;
    for (int a = 1; a < 4; ++a) dm.col(a - 1) = rest_positions_mm[static_cast<std::size_t>(t[a])] - x0;
    const double vol = dm.determinant() / 6.0;
    if (!(vol > 0.0))
      throw InvalidInput("FEM model: tetrahedron " + std::to_string(e) +
                         (vol < 0.0 ? " is inverted in the rest shape" : " is degenerate in the rest shape"));
    m_dm_inv[e] = dm.inverse();
    m_volume[e] = vol;
  }
  detail::build_gather(targets, static_cast<std::size_t>(max_index + 1), m_offsets, m_sources);
}

std::array<Vec3, 4> TetFemModel::gradients(std::size_t e) const {
  std::array<Vec3, 4> b;
  for (int a = 1; a < 4; ++a) b[static_cast<std::size_t>(a)] = m_dm_inv[e].row(a - 1).transpose();
  b[0] = -(b[1] + b[2] + b[3]);
  return b;
}

namespace {
void project_definite(std::span<Mat3, 16> k) {
  Eigen::Matrix<double, 12, 12> m;
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) m.block<3, 3>(3 * a, 3 * b) = k[static_cast<std::size_t>(4 * a + b)];
  m = 0.5 * (m + m.transpose()).eval();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 12, 12>> eig(m);
  if (eig.eigenvalues().minCoeff() >= 0.0) return;
  const Eigen::Matrix<double, 12, 1> lam = eig.eigenvalues().cwiseMax(0.0);
  m = eig.eigenvectors() * lam.asDiagonal() * eig.eigenvectors().transpose();
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) k[static_cast<std::size_t>(4 * a + b)] = m.block<3, 3>(3 * a, 3 * b);
}
}  // namespace

void TetFemModel::update_state(const Particles&, bool) const {}

std::vector<Mat3> TetFemModel::deformation_gradients(const Particles& particles) const {
  const auto& x = particles.positions();
  std::vector<Mat3> out(m_tets.size());
  for (std::size_t e = 0; e < m_tets.size(); ++e) {
    const auto& t = m_tets[e];
    const Vec3& x0 = x[static_cast<std::size_t>(t[0])];
    Mat3 ds;
    for (int a = 1; a < 4; ++a) ds.col(a - 1) = x[static_cast<std::size_t>(t[static_cast<std::size_t>(a)])] - x0;
    out[e] = ds * m_dm_inv[e];
  }
  return out;
}

namespace {
Mat3 deformation_gradient(const std::vector<Vec3>& x, const Tet& t, const Mat3& dm_inv) {
  const Vec3& x0 = x[static_cast<std::size_t>(t[0])];
  Mat3 ds;
  ds.col(0) = x[static_cast<std::size_t>(t[1])] - x0;
  ds.col(1) = x[static_cast<std::size_t>(t[2])] - x0;
  ds.col(2) = x[static_cast<std::size_t>(t[3])] - x0;
  return ds * dm_inv;
}
}  // namespace

void TetFemModel::add_forces(const Particles& particles, std::span<Vec3> forces_n,
                             bool threaded) const {
  update_state(particles, threaded);
  const auto& x = particles.positions();
  auto& slots = m_force_scratch;
  slots.resize(4 * m_tets.size());
  parallel_for(
      m_tets.size(),
      [&](std::size_t e) {
        const Mat3 F = deformation_gradient(x, m_tets[e], m_dm_inv[e]);
        const Mat3 h = -m_volume[e] * first_piola(e, F) * m_dm_inv[e].transpose();
        slots[4 * e + 1] = h.col(0);
        slots[4 * e + 2] = h.col(1);
        slots[4 * e + 3] = h.col(2);
        slots[4 * e] = -(h.col(0) + h.col(1) + h.col(2));
      },
      threaded, 512);
  detail::gather_add(m_offsets, m_sources, slots, forces_n, threaded);
}

double TetFemModel::energy(const Particles& particles) const {
  const auto& x = particles.positions();
  std::vector<double> e_elem(m_tets.size());
  for (std::size_t e = 0; e < m_tets.size(); ++e)
    e_elem[e] = m_volume[e] * energy_density(e, deformation_gradient(x, m_tets[e], m_dm_inv[e]));
  return detail::ordered_sum(e_elem);
}

void TetFemModel::set_material(const ElasticMaterial& material) {
  check_material(material, kind());
  m_lame = lame_parameters(material);
  m_material = material;
}

void TetFemModel::set_youngs_modulus(double youngs_modulus_pa) {
  ElasticMaterial m = m_material;
  m.youngs_modulus_pa = youngs_modulus_pa;
  set_material(m);
}

void TetFemModel::set_poisson_ratio(double poisson_ratio) {
  ElasticMaterial m = m_material;
  m.poisson_ratio = poisson_ratio;
  set_material(m);
}

std::vector<BlockIndex> TetFemModel::stiffness_pattern() const {
  std::vector<BlockIndex> p;
  p.reserve(16 * m_tets.size());
  for (const auto& t : m_tets)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) p.push_back({t[static_cast<std::size_t>(a)], t[static_cast<std::size_t>(b)]});
  return p;
}

void TetFemModel::element_stiffness(std::size_t e, const Mat3& F, const std::array<Vec3, 4>& b,
                                    std::span<Mat3, 16> out) const {
  // K_ab[:, j] = V dP(e_j b_bᵀ) b_a, since f_a = −V P b_a.
  for (int bb = 0; bb < 4; ++bb)
    for (int j = 0; j < 3; ++j) {
      const Mat3 dF = Vec3::Unit(j) * b[static_cast<std::size_t>(bb)].transpose();
      const Mat3 dP = dP_dF(e, F, dF);
      for (int a = 0; a < 4; ++a)
        out[static_cast<std::size_t>(4 * a + bb)].col(j) = m_volume[e] * (dP * b[static_cast<std::size_t>(a)]);
    }
}

void TetFemModel::stiffness_blocks(const Particles& particles, std::span<Mat3> blocks,
                                   bool threaded) const {
  update_state(particles, threaded);
  const auto& x = particles.positions();
  parallel_for(
      m_tets.size(),
      [&](std::size_t e) {
        const Mat3 F = deformation_gradient(x, m_tets[e], m_dm_inv[e]);
        std::span<Mat3, 16> k(blocks.data() + 16 * e, 16);
        element_stiffness(e, F, gradients(e), k);
        if (m_definite) project_definite(k);
      },
      threaded, 256);
}

void TetFemModel::add_stiffness_to(const Particles& particles, std::span<const std::int32_t> slots,
                                   std::span<Mat3> values, bool threaded) const {
  if (slots.size() != 16 * m_tets.size())
    throw InvalidInput("FEM model: stiffness slot list does not match the pattern");
  update_state(particles, threaded);
  const auto& x = particles.positions();
  auto scatter = [&](std::size_t e, std::span<const Mat3, 16> k) {
    for (std::size_t j = 0; j < 16; ++j) {
      const auto s = slots[16 * e + j];
      if (s >= 0) values[static_cast<std::size_t>(s)] += k[j];
    }
  };
  if (!threaded) {
    // One pass: each element's blocks go straight into the matrix.
    std::array<Mat3, 16> k;
    for (std::size_t e = 0; e < m_tets.size(); ++e) {
      const Mat3 F = deformation_gradient(x, m_tets[e], m_dm_inv[e]);
      element_stiffness(e, F, gradients(e), k);
      if (m_definite) project_definite(k);
      scatter(e, k);
    }
    return;
  }
  // Elements in parallel into a scratch buffer, then added in the same order as above (the
  // sums are bit-identical to the serial pass).
  m_block_scratch.resize(16 * m_tets.size());
  stiffness_blocks(particles, m_block_scratch, true);
  for (std::size_t e = 0; e < m_tets.size(); ++e)
    scatter(e, std::span<const Mat3, 16>(m_block_scratch.data() + 16 * e, 16));
}

std::optional<ElementFields> TetFemModel::element_fields(const Particles& particles) const {
  const auto& x = particles.positions();
  ElementFields out;
  out.green_strain.resize(m_tets.size());
  out.cauchy_stress_pa.resize(m_tets.size());
  out.von_mises_pa.resize(m_tets.size());
  for (std::size_t e = 0; e < m_tets.size(); ++e) {
    const Mat3 F = deformation_gradient(x, m_tets[e], m_dm_inv[e]);
    out.green_strain[e] = 0.5 * (F.transpose() * F - Mat3::Identity());
    const double j = F.determinant();
    const Mat3 pft = first_piola(e, F) * F.transpose();
    const Mat3 sigma = (std::abs(j) > 1e-12 ? pft / j : pft) / kPascalToNPerMm2;
    out.cauchy_stress_pa[e] = 0.5 * (sigma + sigma.transpose());
    out.von_mises_pa[e] = von_mises(out.cauchy_stress_pa[e]);
  }
  return out;
}

}  // namespace ido::sim
