// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <algorithm>

#include "ido/core/math.h"
#include "ido/drill/collision.h"

namespace ido::drill {

/// Virtual coupling between the haptic device and the tool proxy.
struct CouplingOptions {
  double stiffness_n_per_mm = 1.5;   ///< coupling spring (N/mm)
  double time_constant_s = 0.004;    ///< first-order filter of the proxy offset (s); 0 = none
  double max_force_n = 10.0;         ///< output clamp (N)
  double model_validity_mm = 2.0;    ///< extrapolate a contact model at most this far (mm)
};

/// Penetration of the device position @p device_mm extrapolated from @p model (mm, ≥ 0):
/// depth_mm − normal · (device − position_mm), clamped at 0. A half-space model only holds
/// near where it was made: farther than @p validity_mm from position_mm it gives 0 (the
/// device jumped; the next collision update brings a fresh model).
[[nodiscard]] inline double extrapolated_depth(const ContactModel& model, const Vec3& device_mm,
                                               double validity_mm = 1e300) noexcept {
  if (!model.in_contact) return 0.0;
  if ((device_mm - model.position_mm).squaredNorm() > validity_mm * validity_mm) return 0.0;
  return std::max(0.0, model.depth_mm - model.normal.dot(device_mm - model.position_mm));
}

/// Proxy-based virtual coupling (Colgate, Stanley & Brown, "Issues in the haptic display of
/// tool use", IROS 1995; proxy after Zilles & Salisbury 1995): the proxy is the device
/// position pushed out of the latest contact half-space; the offset proxy − device goes
/// through a first-order filter (the coupling's damper), so a new contact model never makes
/// the force jump; force = k · offset, clamped. Real-time safe: no allocation, no throw.
class VirtualCoupling {
 public:
  explicit VirtualCoupling(const CouplingOptions& options = {}) noexcept : m_options(options) {}

  /// One haptic tick of @p dt_s seconds with the device at @p device_mm; returns the force
  /// on the device (N).
  Vec3 update(const ContactModel& model, const Vec3& device_mm, double dt_s) noexcept;
  /// Last force (N).
  [[nodiscard]] const Vec3& force() const noexcept { return m_force; }
  /// Proxy offset (mm).
  [[nodiscard]] const Vec3& offset() const noexcept { return m_offset; }
  void reset() noexcept {
    m_offset.setZero();
    m_force.setZero();
  }
  [[nodiscard]] const CouplingOptions& options() const noexcept { return m_options; }

 private:
  CouplingOptions m_options;
  Vec3 m_offset = Vec3::Zero();
  Vec3 m_force = Vec3::Zero();
};

}  // namespace ido::drill
