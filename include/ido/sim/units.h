// SPDX-License-Identifier: Apache-2.0
#pragma once

/// Unit conventions of the simulation library.
///
/// Lengths are millimetres, time seconds, mass kilograms, force newtons. These four are not
/// a coherent system (1 N = 1 kg·m/s² = 1000 kg·mm/s²), so the library converts in exactly
/// these places, through the constants below:
/// - acceleration (mm/s²) = force (N) / (mass (kg) · kKgMmPerS2ToNewton);
/// - kinetic energy (mJ = N·mm) = ½ m v² · kKgMmPerS2ToNewton;
/// - stresses and moduli are given in Pa (N/m²) and used internally in N/mm² (MPa).
/// Elastic energies are in millijoules (N·mm).
namespace ido::sim {

/// One kg·mm/s² expressed in newtons.
inline constexpr double kKgMmPerS2ToNewton = 1e-3;
/// One pascal (N/m²) expressed in N/mm².
inline constexpr double kPascalToNPerMm2 = 1e-6;
/// One kg/m³ expressed in kg/mm³.
inline constexpr double kKgPerM3ToKgPerMm3 = 1e-9;
/// Standard gravity in mm/s².
inline constexpr double kStandardGravityMmPerS2 = 9806.65;

}  // namespace ido::sim
