// SPDX-License-Identifier: Apache-2.0
#include "ido/sim/fem_corotational.h"

namespace ido::sim {

CorotationalFem::CorotationalFem(std::vector<Tet> tets, std::span<const Vec3> rest_positions_mm,
                                 const ElasticMaterial& material)
    : TetFemModel(std::move(tets), rest_positions_mm, material),
      m_rotation(m_tets.size(), Eigen::Quaterniond::Identity()),
      m_previous(m_tets.size(), Eigen::Quaterniond::Identity()),
      m_cached(m_tets.size()) {}

Mat3 CorotationalFem::rotation(std::size_t e, const Mat3& F) const {
  auto& c = m_cached[e];
  if (c.F == F) return c.R;   // same positions as the last call: same (deterministic) result
  // Warm start: the last rotation advanced by the last change (q (q₋₁⁻¹ q)), one Newton
  // iteration fewer than starting from q when the element turns smoothly.
  auto& q = m_rotation[e];
  const Eigen::Quaterniond last = q;
  q = (q * (m_previous[e].conjugate() * q)).normalized();
  m_previous[e] = last;
  c.R = extract_rotation(F, q);
  c.F = F;
  return c.R;
}

double CorotationalFem::energy_density(std::size_t e, const Mat3& F) const {
  const Mat3 r = rotation(e, F);
  const double tr = (r.transpose() * F).trace() - 3.0;
  return m_lame.mu * (F - r).squaredNorm() + 0.5 * m_lame.lambda * tr * tr;
}

Mat3 CorotationalFem::first_piola(std::size_t e, const Mat3& F) const {
  const Mat3 r = rotation(e, F);
  const double tr = (r.transpose() * F).trace() - 3.0;
  return 2.0 * m_lame.mu * (F - r) + m_lame.lambda * tr * r;
}

Mat3 CorotationalFem::dP_dF(std::size_t e, const Mat3& F, const Mat3& dF) const {
  const Mat3 r = rotation(e, F);
  const Mat3 g = r.transpose() * dF;
  return r * (m_lame.mu * (g + g.transpose()) + m_lame.lambda * g.trace() * Mat3::Identity());
}

void CorotationalFem::element_stiffness(std::size_t e, const Mat3& F, const std::array<Vec3, 4>& b,
                                        std::span<Mat3, 16> out) const {
  // R K₀_ab Rᵀ = V [μ (b_a·b_b) I + μ (R b_b)(R b_a)ᵀ + λ (R b_a)(R b_b)ᵀ]
  const Mat3 r = rotation(e, F);
  std::array<Vec3, 4> rb;
  for (std::size_t a = 0; a < 4; ++a) rb[a] = r * b[a];
  const double v = m_volume[e], mu = m_lame.mu, la = m_lame.lambda;
  // K_ca = K_acᵀ: compute the upper block triangle and transpose it.
  for (std::size_t a = 0; a < 4; ++a)
    for (std::size_t c = a; c < 4; ++c) {
      Mat3 k = (v * mu) * rb[c] * rb[a].transpose() + (v * la) * rb[a] * rb[c].transpose();
      k.diagonal().array() += v * mu * b[a].dot(b[c]);
      out[4 * a + c] = k;
      if (c != a) out[4 * c + a] = k.transpose();
    }
}

}  // namespace ido::sim
