// SPDX-License-Identifier: Apache-2.0
// The SOR kernels of implicit Euler's CG (private, src/sim/sor_kernels.h): the dispatched
// (AVX2/FMA where available) and the portable versions solve their triangular systems.
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "../../src/sim/sor_kernels.h"
#include "ido/core/math.h"
#include "support/test_support.h"

namespace ido {
namespace {

using RowMajor3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

// A random upper block triangle on a 1-D chain with a few long-range couplings, dominant
// SPD diagonal blocks; vectors 4 doubles a row with a zero fourth lane.
struct Fixture {
  std::size_t rows = 57;
  std::vector<std::int32_t> row_offset, col;
  std::vector<Mat3> blocks, dtilde;
  std::vector<double> blocks_rm, dinv_rm;
  sim::detail::SorMatrix matrix() const {
    return {rows, row_offset.data(), col.data(), blocks_rm.data(), dinv_rm.data()};
  }
  Fixture() {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    row_offset.push_back(0);
    for (std::size_t i = 0; i < rows; ++i) {
      Mat3 a;
      for (int k = 0; k < 9; ++k) a(k / 3, k % 3) = u(rng);
      col.push_back(static_cast<std::int32_t>(i));
      blocks.push_back(Mat3::Zero());   // diagonal slot, not read
      for (std::size_t j : {i + 1, i + 2, i + 9, i + 20})
        if (j < rows) {
          col.push_back(static_cast<std::int32_t>(j));
          Mat3 b;
          for (int k = 0; k < 9; ++k) b(k / 3, k % 3) = u(rng);
          blocks.push_back(b);
        }
      row_offset.push_back(static_cast<std::int32_t>(col.size()));
      dtilde.push_back(a * a.transpose() + 8.0 * Mat3::Identity());
    }
    blocks_rm.assign(9 * blocks.size() + 3, 0.0);
    for (std::size_t k = 0; k < blocks.size(); ++k)
      Eigen::Map<RowMajor3>(blocks_rm.data() + 9 * k) = blocks[k];
    dinv_rm.assign(9 * rows + 3, 0.0);
    for (std::size_t i = 0; i < rows; ++i)
      Eigen::Map<RowMajor3>(dinv_rm.data() + 9 * i) = dtilde[i].inverse();
  }
  std::vector<double> random_vector(std::mt19937& rng) const {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<double> v(4 * rows, 0.0);
    for (std::size_t i = 0; i < rows; ++i)
      for (int c = 0; c < 3; ++c) v[4 * i + static_cast<std::size_t>(c)] = u(rng);
    return v;
  }
  static Vec3 row(const std::vector<double>& v, std::size_t i) {
    return Vec3(v[4 * i], v[4 * i + 1], v[4 * i + 2]);
  }
};

void check_backward(bool portable) {
  Fixture f;
  std::mt19937 rng(11);
  const auto sigma = f.random_vector(rng);
  auto p = f.random_vector(rng);
  const auto p_in = p;
  std::vector<double> s(4 * f.rows, 0.0), t(4 * f.rows, 0.0), g(4 * f.rows, 0.0);
  const double beta = 0.37, om2 = 1.3 - 2.0;
  if (portable)
    sim::detail::sor_backward_portable(f.matrix(), sigma.data(), beta, om2, p.data(), s.data(), t.data(), g.data());
  else
    sim::detail::sor_backward(f.matrix(), sigma.data(), beta, om2, p.data(), s.data(), t.data(), g.data());
  // (D̃ + U) t = p with p = σ + β p_in; s = D̃ t; g = p + (ω − 2) s; fourth lanes stay 0.
  double err = 0.0;
  for (std::size_t i = 0; i < f.rows; ++i) {
    const Vec3 pi = Fixture::row(sigma, i) + beta * Fixture::row(p_in, i);
    Vec3 lhs = f.dtilde[i] * Fixture::row(t, i);
    for (auto k = f.row_offset[i] + 1; k < f.row_offset[i + 1]; ++k)
      lhs += f.blocks[static_cast<std::size_t>(k)] * Fixture::row(t, static_cast<std::size_t>(f.col[static_cast<std::size_t>(k)]));
    err = std::max({err, (lhs - pi).norm(), (Fixture::row(p, i) - pi).norm(),
                    (Fixture::row(s, i) - f.dtilde[i] * Fixture::row(t, i)).norm(),
                    (Fixture::row(g, i) - (pi + om2 * Fixture::row(s, i))).norm()});
    EXPECT_EQ(p[4 * i + 3], 0.0);
    EXPECT_EQ(s[4 * i + 3], 0.0);
    EXPECT_EQ(t[4 * i + 3], 0.0);
    EXPECT_EQ(g[4 * i + 3], 0.0);
  }
  EXPECT_TRUE(test::near(err, 0.0, 1e-12)) << err;
}

void check_forward(bool portable) {
  Fixture f;
  std::mt19937 rng(13);
  const auto g_in = f.random_vector(rng);
  auto g = g_in;
  std::vector<double> w(4 * f.rows, 0.0);
  if (portable)
    sim::detail::sor_forward_portable(f.matrix(), g.data(), w.data());
  else
    sim::detail::sor_forward(f.matrix(), g.data(), w.data());
  // (D̃ + Uᵀ) w = g_in, and g ends as D̃ w.
  std::vector<Vec3> lhs(f.rows);
  for (std::size_t i = 0; i < f.rows; ++i) lhs[i] = f.dtilde[i] * Fixture::row(w, i);
  for (std::size_t i = 0; i < f.rows; ++i)
    for (auto k = f.row_offset[i] + 1; k < f.row_offset[i + 1]; ++k)
      lhs[static_cast<std::size_t>(f.col[static_cast<std::size_t>(k)])] +=
          f.blocks[static_cast<std::size_t>(k)].transpose() * Fixture::row(w, i);
  double err = 0.0;
  for (std::size_t i = 0; i < f.rows; ++i) {
    err = std::max({err, (lhs[i] - Fixture::row(g_in, i)).norm(),
                    (Fixture::row(g, i) - f.dtilde[i] * Fixture::row(w, i)).norm()});
    EXPECT_EQ(w[4 * i + 3], 0.0);
    EXPECT_EQ(g[4 * i + 3], 0.0);
  }
  EXPECT_TRUE(test::near(err, 0.0, 1e-12)) << err;
}

TEST(SorKernels, BackwardPassSolvesTheUpperSystem) { check_backward(false); }
TEST(SorKernels, PortableBackwardPassSolvesTheUpperSystem) { check_backward(true); }
TEST(SorKernels, ForwardPassSolvesTheLowerSystem) { check_forward(false); }
TEST(SorKernels, PortableForwardPassSolvesTheLowerSystem) { check_forward(true); }

TEST(SorKernels, UpdateAndDotMatchAPlainLoop) {
  Fixture f;
  std::mt19937 rng(17);
  const auto t = f.random_vector(rng), s = f.random_vector(rng), g = f.random_vector(rng);
  auto q = f.random_vector(rng), x = f.random_vector(rng), rho = f.random_vector(rng),
       sigma = f.random_vector(rng);
  const auto p = f.random_vector(rng);
  const auto q0 = q, x0 = x, rho0 = rho, sigma0 = sigma;
  const double pq = sim::detail::sor_add_dot(f.rows, q.data(), t.data(), p.data());
  const double alpha = 0.61;
  const double rs = sim::detail::sor_update(f.rows, alpha, t.data(), q.data(), s.data(), g.data(),
                                       x.data(), rho.data(), sigma.data());
  double pq_ref = 0.0, rs_ref = 0.0, err = 0.0;
  for (std::size_t k = 0; k < q.size(); ++k) {
    const double qk = q0[k] + t[k];
    pq_ref += p[k] * qk;
    const double rk = rho0[k] - alpha * qk, sk = sigma0[k] - alpha * (s[k] + g[k]);
    rs_ref += rk * sk;
    err = std::max({err, std::abs(q[k] - qk), std::abs(x[k] - (x0[k] + alpha * t[k])),
                    std::abs(rho[k] - rk), std::abs(sigma[k] - sk)});
  }
  EXPECT_TRUE(test::near(err, 0.0, 1e-14));
  EXPECT_TRUE(test::near(pq, pq_ref, 1e-12));
  EXPECT_TRUE(test::near(rs, rs_ref, 1e-12));
}

}  // namespace
}  // namespace ido
