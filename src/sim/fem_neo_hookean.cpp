// SPDX-License-Identifier: Apache-2.0
#include "ido/sim/fem_neo_hookean.h"

namespace ido::sim {

namespace {
Mat3 cofactor(const Mat3& F) {
  Mat3 c;
  c.col(0) = F.col(1).cross(F.col(2));
  c.col(1) = F.col(2).cross(F.col(0));
  c.col(2) = F.col(0).cross(F.col(1));
  return c;
}
}  // namespace

double NeoHookeanFem::energy_density(std::size_t, const Mat3& F) const {
  const double lp = m_lame.lambda + m_lame.mu;
  const double alpha = 1.0 + m_lame.mu / lp;
  const double j = F.determinant();
  return 0.5 * m_lame.mu * (F.squaredNorm() - 3.0) + 0.5 * lp * (j - alpha) * (j - alpha) -
         0.5 * lp * (1.0 - alpha) * (1.0 - alpha);
}

Mat3 NeoHookeanFem::first_piola(std::size_t, const Mat3& F) const {
  const double lp = m_lame.lambda + m_lame.mu;
  const double alpha = 1.0 + m_lame.mu / lp;
  return m_lame.mu * F + lp * (F.determinant() - alpha) * cofactor(F);
}

Mat3 NeoHookeanFem::dP_dF(std::size_t, const Mat3& F, const Mat3& dF) const {
  const double lp = m_lame.lambda + m_lame.mu;
  const double alpha = 1.0 + m_lame.mu / lp;
  const Mat3 cof = cofactor(F);
  Mat3 dcof;
  dcof.col(0) = dF.col(1).cross(F.col(2)) + F.col(1).cross(dF.col(2));
  dcof.col(1) = dF.col(2).cross(F.col(0)) + F.col(2).cross(dF.col(0));
  dcof.col(2) = dF.col(0).cross(F.col(1)) + F.col(0).cross(dF.col(1));
  return m_lame.mu * dF + lp * cof.cwiseProduct(dF).sum() * cof +
         lp * (F.determinant() - alpha) * dcof;
}

}  // namespace ido::sim
