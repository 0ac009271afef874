// SPDX-License-Identifier: Apache-2.0
// The tool: Fibonacci samples on the burr (unit radius times r, evenly spread, cap fractions
// equal cap areas), shaft rings at the same spacing, and the option checks and parser.
#include "ido/drill/tool.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

TEST(Tool, FibonacciSamplesAreEvenlySpread) {
  const Tool tool({.burr_radius_mm = 2.0, .sample_count = 1000});
  ASSERT_EQ(tool.burr_samples().size(), 1000U);
  Vec3 mean = Vec3::Zero();
  for (const auto& s : tool.burr_samples()) {
    EXPECT_TRUE(test::near(s.norm(), 2.0, 1e-12));
    mean += s;
  }
  EXPECT_LT((mean / 1000.0).norm(), 1e-3);
  // Cap fractions match cap areas (d / 2r) within 1 %.
  for (double d : {0.1, 0.5, 1.0, 2.0, 3.0}) {
    int n = 0;
    for (const auto& s : tool.burr_samples()) n += s.z() < -2.0 + d ? 1 : 0;
    EXPECT_TRUE(test::near(n / 1000.0, d / 4.0, 0.01)) << "depth " << d;
  }
  EXPECT_EQ(parse_tool("sphere:radius=1.5,shaft=0.5").shaft_radius_mm, 0.5);
  EXPECT_THROW((void)parse_tool("sphere:radius=1,shaft=2"), InvalidInput);
  EXPECT_THROW((void)parse_tool("cube:radius=1"), InvalidInput);
  EXPECT_THROW((void)parse_tool("sphere:shaft=0.2"), InvalidInput);
  EXPECT_THROW((void)parse_tool("sphere:radius=abc"), InvalidInput);
}
TEST(Tool, FibonacciSphereIsUnitAndSymmetric) {
  for (const int n : {1, 2, 20, 377, 1000}) {
    const auto p = fibonacci_sphere(n);
    ASSERT_EQ(p.size(), std::size_t(n));
    Vec3 sum = Vec3::Zero();
    for (const Vec3& u : p) {
      EXPECT_TRUE(test::near(u.norm(), 1.0, 1e-12));
      sum += u;
    }
    // z = 1 − (2i + 1)/n: evenly spaced heights, symmetric about 0 (Archimedes: equal areas).
    for (int i = 0; i < n; ++i) EXPECT_TRUE(test::near(p[std::size_t(i)].z(), 1.0 - (2.0 * i + 1.0) / n, 1e-12));
    EXPECT_TRUE(test::near(sum.z(), 0.0, 1e-9));
  }
  // Nearest-neighbour distances are all alike (evenly spread): within a factor 1.6 of each other.
  const auto p = fibonacci_sphere(500);
  double lo = 1e9, hi = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    double nearest = 1e9;
    for (std::size_t j = 0; j < p.size(); ++j)
      if (j != i) nearest = std::min(nearest, (p[i] - p[j]).norm());
    lo = std::min(lo, nearest);
    hi = std::max(hi, nearest);
  }
  EXPECT_LT(hi / lo, 1.6);
}

TEST(Tool, ShaftRingsLieOnTheCylinderFromTheBurrOutward) {
  const ToolOptions o{.burr_radius_mm = 2.0, .shaft_radius_mm = 0.8, .shaft_length_mm = 20.0, .sample_count = 800};
  const Tool tool(o);
  EXPECT_EQ(tool.burr_radius(), 2.0);
  EXPECT_EQ(tool.options().shaft_radius_mm, 0.8);
  const int ring = tool.shaft_ring_size();
  ASSERT_GE(ring, 6);
  ASSERT_FALSE(tool.shaft_samples().empty());
  ASSERT_EQ(tool.shaft_samples().size() % std::size_t(ring), 0U);
  // The burr's sample spacing √(4π r² / n); rings that far apart around the circumference.
  const double spacing = std::sqrt(4.0 * kPi * 4.0 / 800.0);
  EXPECT_LE(2.0 * kPi * 0.8 / ring, spacing + 1e-12);
  const double z_exit = std::sqrt(4.0 - 0.64);  // where the shaft leaves the burr
  double last_z = 0.0;
  for (std::size_t k = 0; k < tool.shaft_samples().size(); ++k) {
    const Vec3& s = tool.shaft_samples()[k];
    EXPECT_TRUE(test::near(std::hypot(s.x(), s.y()), 0.8, 1e-12));
    EXPECT_GT(s.z(), z_exit);  // outside the burr
    EXPECT_LE(s.z(), 20.0);
    if (k % std::size_t(ring) == 0) {
      if (k > 0) {
        EXPECT_TRUE(test::near(s.z() - last_z, spacing, 1e-9));
      }
      last_z = s.z();
    } else {
      EXPECT_EQ(s.z(), last_z) << "a ring is at one height";
    }
  }
  // The last ring is within one spacing of the shaft's end.
  EXPECT_GT(last_z, 20.0 - spacing);
  // Without a shaft: no rings.
  const Tool bare({.burr_radius_mm = 1.0});
  EXPECT_EQ(bare.shaft_ring_size(), 0);
  EXPECT_TRUE(bare.shaft_samples().empty());
  EXPECT_EQ(bare.burr_samples().size(), 1000U);
}

// The message of an InvalidInput thrown by @p f, or "no error".
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "no error";
}

TEST(Tool, BadOptionsAndSpecsAreRefusedNamingTheProblem) {
  EXPECT_NE(error_of([] { Tool t({.burr_radius_mm = 0.0}); }).find("burr radius"), std::string::npos);
  EXPECT_NE(error_of([] { Tool t({.burr_radius_mm = -1.0}); }).find("burr radius"), std::string::npos);
  EXPECT_NE(error_of([] { Tool t({.burr_radius_mm = std::nan("")}); }).find("burr radius"), std::string::npos);
  EXPECT_NE(error_of([] { Tool t({.sample_count = 19}); }).find("20"), std::string::npos);
  EXPECT_EQ(error_of([] { Tool t({.sample_count = 20}); }), "no error");
  EXPECT_NE(error_of([] { Tool t({.burr_radius_mm = 1.0, .shaft_radius_mm = 1.0}); }).find("shaft radius"), std::string::npos);
  EXPECT_NE(error_of([] { Tool t({.burr_radius_mm = 1.0, .shaft_radius_mm = -0.1}); }).find("shaft radius"), std::string::npos);
  EXPECT_NE(error_of([] { Tool t({.burr_radius_mm = 1.0, .shaft_radius_mm = 0.5, .shaft_length_mm = 0.0}); }).find("shaft length"),
            std::string::npos);
  // The parser names the whole spec and the offending part.
  const std::string bad_number = error_of([] { (void)parse_tool("sphere:radius=2,shaft=thin"); });
  EXPECT_NE(bad_number.find("sphere:radius=2,shaft=thin"), std::string::npos) << bad_number;
  EXPECT_NE(bad_number.find("'thin'"), std::string::npos) << bad_number;
  EXPECT_NE(error_of([] { (void)parse_tool("sphere:radius=2,colour=3"); }).find("unknown key 'colour'"), std::string::npos);
  EXPECT_NE(error_of([] { (void)parse_tool("sphere:radius=2,colour=red"); }).find("'red' is not a number"), std::string::npos);
  EXPECT_NE(error_of([] { (void)parse_tool("sphere:radius"); }).find("'radius' is not key=value"), std::string::npos);
  EXPECT_NE(error_of([] { (void)parse_tool("sphere:samples=50"); }).find("radius=MM is required"), std::string::npos);
  EXPECT_NE(error_of([] { (void)parse_tool("sphere:radius=2,samples=5"); }).find("20"), std::string::npos);
  EXPECT_NE(error_of([] { (void)parse_tool("sphere:radius=inf"); }).find("'inf'"), std::string::npos);
  // A full spec reads back every field.
  const ToolOptions o = parse_tool("sphere:radius=2.5,shaft=0.75,samples=400");
  EXPECT_EQ(o.burr_radius_mm, 2.5);
  EXPECT_EQ(o.shaft_radius_mm, 0.75);
  EXPECT_EQ(o.sample_count, 400);
  EXPECT_EQ(parse_tool("sphere:radius=1").shaft_radius_mm, 0.0);
}

}  // namespace
}  // namespace ido::drill
