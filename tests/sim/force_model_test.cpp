// SPDX-License-Identifier: Apache-2.0
// What ForceModel gives every model from its stiffness blocks: the sparse matrix (blocks at
// their pattern's places, repeated places summed), the product K·dx, the default assembly into
// slots (negative slots skipped), and the defaults of a model without stiffness or elements.
#include "ido/sim/force_model.h"

#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "support/test_support.h"

namespace ido {
namespace {

/// A model with fixed stiffness blocks (forces −K x, energy ½ xᵀ K x): the pattern lists the
/// block (0, 0) twice, as element models do for a particle shared by two elements.
class FixedBlocks final : public sim::ForceModel {
 public:
  FixedBlocks() {
    for (int k = 0; k < 5; ++k) {
      Mat3 b;
      b << 1 + k, 2, 3 * k, -k, 5, 0.5, 7, -1, 2 * k;
      m_blocks.push_back(b);
    }
  }
  [[nodiscard]] std::string_view kind() const override { return "fixed_blocks"; }
  void add_forces(const sim::Particles&, std::span<Vec3>, bool) const override {}
  [[nodiscard]] double energy(const sim::Particles&) const override { return 0.0; }
  [[nodiscard]] std::vector<sim::BlockIndex> stiffness_pattern() const override {
    return {{0, 0}, {0, 2}, {2, 0}, {2, 2}, {0, 0}};
  }
  void stiffness_blocks(const sim::Particles&, std::span<Mat3> blocks, bool) const override {
    for (std::size_t k = 0; k < blocks.size(); ++k) blocks[k] = m_blocks[k];
  }
  std::vector<Mat3> m_blocks;
};

/// A model with no stiffness and no elements.
class NoStiffness final : public sim::ForceModel {
 public:
  [[nodiscard]] std::string_view kind() const override { return "none"; }
  void add_forces(const sim::Particles&, std::span<Vec3>, bool) const override {}
  [[nodiscard]] double energy(const sim::Particles&) const override { return 0.0; }
};

sim::Particles three_particles() {
  sim::Particles p;
  for (int i = 0; i < 3; ++i) p.add(Vec3(i, 0, 0), 1.0);
  return p;
}

TEST(ForceModel, StiffnessMatrixPutsEachBlockInItsPlaceAndSumsRepeats) {
  const FixedBlocks model;
  const auto p = three_particles();
  const Eigen::MatrixXd k = Eigen::MatrixXd(model.stiffness_matrix(p));
  ASSERT_EQ(k.rows(), 9);
  ASSERT_EQ(k.cols(), 9);
  Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(9, 9);
  expected.block<3, 3>(0, 0) = model.m_blocks[0] + model.m_blocks[4];
  expected.block<3, 3>(0, 6) = model.m_blocks[1];
  expected.block<3, 3>(6, 0) = model.m_blocks[2];
  expected.block<3, 3>(6, 6) = model.m_blocks[3];
  EXPECT_EQ(k, expected);
  EXPECT_TRUE(model.has_stiffness());

  // K·dx from the blocks equals the matrix's product, added to what is there.
  const std::vector<Vec3> dx = {Vec3(1, -2, 3), Vec3(40, 50, 60), Vec3(-0.5, 0.25, 2)};
  std::vector<Vec3> out(3, Vec3(1, 1, 1));
  model.add_stiffness_product(p, dx, out);
  Eigen::VectorXd x(9);
  for (int i = 0; i < 3; ++i) x.segment<3>(3 * i) = dx[std::size_t(i)];
  const Eigen::VectorXd kx = expected * x;
  for (int i = 0; i < 3; ++i)
    EXPECT_TRUE(test::near((out[std::size_t(i)] - Vec3(1, 1, 1) - kx.segment<3>(3 * i)).norm(), 0.0, 1e-12)) << i;
}

TEST(ForceModel, DefaultAssemblyAddsBlocksToTheirSlotsAndSkipsNegativeOnes) {
  const FixedBlocks model;
  const auto p = three_particles();
  std::vector<Mat3> values(3, Mat3::Identity());
  const std::vector<std::int32_t> slots = {0, -1, 2, 1, 0};
  model.add_stiffness_to(p, slots, values, false);
  EXPECT_EQ(values[0], Mat3(Mat3::Identity() + model.m_blocks[0] + model.m_blocks[4]));
  EXPECT_EQ(values[1], Mat3(Mat3::Identity() + model.m_blocks[3]));
  EXPECT_EQ(values[2], Mat3(Mat3::Identity() + model.m_blocks[2]));
}

TEST(ForceModel, AModelWithoutStiffnessOrElementsHasNone) {
  const NoStiffness model;
  const auto p = three_particles();
  EXPECT_FALSE(model.has_stiffness());
  EXPECT_EQ(model.stiffness_matrix(p).nonZeros(), 0);
  EXPECT_EQ(model.stiffness_matrix(p).rows(), 9);
  std::vector<Vec3> out(3, Vec3(1, 2, 3));
  model.add_stiffness_product(p, std::vector<Vec3>(3, Vec3(1, 1, 1)), out);
  for (const Vec3& o : out) EXPECT_EQ(o, Vec3(1, 2, 3));
  EXPECT_FALSE(model.element_fields(p).has_value());
}

}  // namespace
}  // namespace ido
