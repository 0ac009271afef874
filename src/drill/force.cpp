// SPDX-License-Identifier: Apache-2.0
#include "ido/drill/force.h"

#include <cmath>

namespace ido::drill {

Vec3 VirtualCoupling::update(const ContactModel& model, const Vec3& device_mm, double dt_s) noexcept {
  const Vec3 target = extrapolated_depth(model, device_mm, m_options.model_validity_mm) * model.normal;
  const double tau = m_options.time_constant_s;
  const double alpha = tau > 0.0 ? 1.0 - std::exp(-std::max(dt_s, 0.0) / tau) : 1.0;
  m_offset += alpha * (target - m_offset);
  m_force = m_options.stiffness_n_per_mm * m_offset;
  const double f = m_force.norm();
  if (f > m_options.max_force_n) m_force *= m_options.max_force_n / f;
  return m_force;
}

}  // namespace ido::drill
