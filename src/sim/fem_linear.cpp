// SPDX-License-Identifier: Apache-2.0
#include "ido/sim/fem_linear.h"

namespace ido::sim {

double LinearFem::energy_density(std::size_t, const Mat3& F) const {
  const Mat3 eps = 0.5 * (F + F.transpose()) - Mat3::Identity();
  const double tr = eps.trace();
  return m_lame.mu * eps.cwiseProduct(eps).sum() + 0.5 * m_lame.lambda * tr * tr;
}

Mat3 LinearFem::first_piola(std::size_t, const Mat3& F) const {
  const Mat3 eps = 0.5 * (F + F.transpose()) - Mat3::Identity();
  return 2.0 * m_lame.mu * eps + m_lame.lambda * eps.trace() * Mat3::Identity();
}

Mat3 LinearFem::dP_dF(std::size_t, const Mat3&, const Mat3& dF) const {
  return m_lame.mu * (dF + dF.transpose()) + m_lame.lambda * dF.trace() * Mat3::Identity();
}

void LinearFem::element_stiffness(std::size_t e, const Mat3&, const std::array<Vec3, 4>& b,
                                  std::span<Mat3, 16> out) const {
  // K_ab = V [μ (b_a·b_b) I + μ b_b b_aᵀ + λ b_a b_bᵀ]
  const double v = m_volume[e], mu = m_lame.mu, la = m_lame.lambda;
  for (std::size_t a = 0; a < 4; ++a)
    for (std::size_t c = 0; c < 4; ++c)
      out[4 * a + c] = v * (mu * b[a].dot(b[c]) * Mat3::Identity() + mu * b[c] * b[a].transpose() +
                            la * b[a] * b[c].transpose());
}

}  // namespace ido::sim
