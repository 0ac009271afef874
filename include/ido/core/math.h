// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

/// Small math aliases shared by every module. Positions are in millimetres unless a name
/// says otherwise.
namespace ido {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Vec4 = Eigen::Vector4d;
using Mat3 = Eigen::Matrix3d;
using Mat4 = Eigen::Matrix4d;
using Vec3f = Eigen::Vector3f;
using Vec3i = Eigen::Vector3i;
using Index3 = std::array<std::int64_t, 3>;
using Tri = std::array<std::int32_t, 3>;
using Tet = std::array<std::int32_t, 4>;
using Edge = std::array<std::int32_t, 2>;

inline constexpr double kPi = 3.14159265358979323846;

}  // namespace ido
