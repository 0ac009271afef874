// SPDX-License-Identifier: Apache-2.0
// Field: values stored entity-major, count() = values / components; FieldMap ordered by name.
#include "ido/geometry/field.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace ido::geometry {
namespace {

TEST(Field, CountIsValuesPerComponentsEntityMajor) {
  Field scalar;  // defaults: one component, no values
  EXPECT_EQ(scalar.components, 1);
  EXPECT_EQ(scalar.count(), 0U);
  scalar.values = {1, 2, 3, 4, 5};
  EXPECT_EQ(scalar.count(), 5U);

  // Displacements of 4 points: entity e, component c at values[e * 3 + c].
  Field displacement{3, {}};
  for (int e = 0; e < 4; ++e)
    for (int c = 0; c < 3; ++c) displacement.values.push_back(10.0 * e + c);
  EXPECT_EQ(displacement.count(), 4U);
  EXPECT_EQ(displacement.values[2 * 3 + 1], 21.0);  // entity 2, component y

  // A partial last entity is not counted; no components means no entities (no division by 0).
  displacement.values.push_back(99.0);
  EXPECT_EQ(displacement.count(), 4U);
  const Field broken{0, {1, 2, 3}};
  EXPECT_EQ(broken.count(), 0U);
  const Field negative{-2, {1, 2, 3}};
  EXPECT_EQ(negative.count(), 0U);
}

TEST(Field, FieldMapIteratesInNameOrderWhateverTheInsertionOrder) {
  // Files are written in this order, so two runs that add fields differently write the same bytes.
  FieldMap a, b;
  const std::vector<std::string> names{"von_mises_pa", "displacement_mm", "Density", "age_s"};
  for (const auto& n : names) a[n] = Field{1, {1.0}};
  for (auto it = names.rbegin(); it != names.rend(); ++it) b[*it] = Field{1, {1.0}};
  std::vector<std::string> order_a, order_b;
  for (const auto& [name, f] : a) order_a.push_back(name);
  for (const auto& [name, f] : b) order_b.push_back(name);
  EXPECT_EQ(order_a, order_b);
  EXPECT_EQ(order_a, (std::vector<std::string>{"Density", "age_s", "displacement_mm", "von_mises_pa"}));
}

}  // namespace
}  // namespace ido::geometry
