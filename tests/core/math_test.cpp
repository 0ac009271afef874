// SPDX-License-Identifier: Apache-2.0
// The shared math aliases: shapes and scalar types every module relies on, and kPi.
#include "ido/core/math.h"

#include <cmath>
#include <cstdint>
#include <numbers>
#include <type_traits>

#include <gtest/gtest.h>

namespace ido {
namespace {

// Positions are double precision millimetres; index triples are 64-bit (volumes past 2^31
// voxels); mesh indices are 32-bit (the file formats' and the drill's packed keys' width).
static_assert(std::is_same_v<Vec3::Scalar, double> && Vec3::RowsAtCompileTime == 3 && Vec3::ColsAtCompileTime == 1);
static_assert(std::is_same_v<Vec2::Scalar, double> && Vec2::RowsAtCompileTime == 2);
static_assert(std::is_same_v<Vec4::Scalar, double> && Vec4::RowsAtCompileTime == 4);
static_assert(std::is_same_v<Mat3::Scalar, double> && Mat3::RowsAtCompileTime == 3 && Mat3::ColsAtCompileTime == 3);
static_assert(std::is_same_v<Mat4::Scalar, double> && Mat4::RowsAtCompileTime == 4 && Mat4::ColsAtCompileTime == 4);
static_assert(std::is_same_v<Vec3f::Scalar, float> && Vec3f::RowsAtCompileTime == 3);
static_assert(std::is_same_v<Vec3i::Scalar, int> && Vec3i::RowsAtCompileTime == 3);
static_assert(std::is_same_v<Index3::value_type, std::int64_t> && std::tuple_size_v<Index3> == 3);
static_assert(std::is_same_v<Tri::value_type, std::int32_t> && std::tuple_size_v<Tri> == 3);
static_assert(std::is_same_v<Tet::value_type, std::int32_t> && std::tuple_size_v<Tet> == 4);
static_assert(std::is_same_v<Edge::value_type, std::int32_t> && std::tuple_size_v<Edge> == 2);

TEST(Math, PiIsTheClosestDouble) {
  EXPECT_EQ(kPi, std::numbers::pi);
  EXPECT_EQ(std::cos(kPi), -1.0);
  EXPECT_EQ(4.0 * std::atan(1.0), kPi);
}

TEST(Math, AliasesBehaveAsEigenVectors) {
  // A right-handed frame: x × y = z; homogeneous Mat4 · Vec4 applies a translation.
  EXPECT_EQ(Vec3::UnitX().cross(Vec3::UnitY()), Vec3::UnitZ());
  Mat4 m = Mat4::Identity();
  m.block<3, 1>(0, 3) = Vec3(1, 2, 3);
  EXPECT_EQ(m * Vec4(1, 1, 1, 1), Vec4(2, 3, 4, 1));
  // Value-initialised index arrays are zero (containers of them start clean).
  const Index3 zero{};
  const Tet none{};
  EXPECT_EQ(zero[0] + zero[1] + zero[2], 0);
  EXPECT_EQ(none[0] + none[1] + none[2] + none[3], 0);
}

}  // namespace
}  // namespace ido
