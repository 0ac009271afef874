// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <vector>

#include "ido/core/math.h"

namespace ido::sim {

/// Rayleigh damping C = α M + β K (Rayleigh, "The Theory of Sound", 1877): the damping
/// force is −C v.
struct RayleighDamping {
  double mass_per_s = 0.0;     ///< α, 1/s
  double stiffness_s = 0.0;    ///< β, s (uses the models' stiffness)
};

/// A constant force on one particle.
struct PointLoad {
  std::int32_t particle = 0;
  Vec3 force_n = Vec3::Zero();
};

/// A rigid, frictionless half-space boundary {x : (x − point) · normal ≥ 0}. After each
/// step, particles below it are projected onto it and their inward normal velocity removed
/// (perfectly inelastic contact).
struct PlaneContact {
  Vec3 point_mm = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();   ///< unit outward normal (normalised on use)
};

/// Forces and constraints that do not come from a force model.
struct ExternalForces {
  Vec3 gravity_mm_s2 = Vec3::Zero();     ///< e.g. (0, 0, −kStandardGravityMmPerS2)
  RayleighDamping damping;
  std::vector<PointLoad> point_loads;
  std::vector<PlaneContact> planes;
};

}  // namespace ido::sim
