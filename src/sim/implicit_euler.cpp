// SPDX-License-Identifier: Apache-2.0
// Implicit Euler in its pieces: the sparsity pattern (built once per model set, particle count
// and fixed set), the assembly of K and of the system matrix A = M' + ak K, the preconditioner's
// diagonal blocks, the warm start, the two preconditioned CG solvers and the velocity / position
// update. The system is symmetric, so only its upper block triangle is stored (BSR, 3×3 blocks,
// rows in solver order, the diagonal block first in each row). Solver order: the free particles
// only (fixed particles do not move; their rows and columns are dropped). Each step refills the
// values, every model adding its blocks straight into their slots in a fixed order
// (deterministic whether threaded or not).
#include "ido/sim/implicit_euler.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Cholesky>

#include "ido/core/error.h"
#include "ido/sim/units.h"
#include "ido/sim/world.h"
#include "sor_kernels.h"

namespace ido::sim {

struct ImplicitEuler::Solver {
  bool valid = false;
  std::uint64_t model_revision = 0;          // World::model_revision() the pattern was built for
  std::size_t particle_count = 0;
  std::vector<std::uint8_t> fixed;           // fixed flags the pattern was built for
  std::vector<std::int32_t> particle_of;     // solver index → particle
  std::vector<std::int32_t> row_offset;      // upper BSR rows, solver order
  std::vector<std::int32_t> col;             // column (solver index) per slot, sorted per row
  std::vector<std::vector<std::int32_t>> model_slots;   // per model: slot of each pattern
                                                        // block, −1 for lower or fixed ones
  std::vector<Mat3> values;                  // K per slot (N/mm), then A = M' + ak K in place
  std::vector<Mat3> dinv;                    // per row: inverse of the preconditioner's
                                             // diagonal block
  std::vector<std::int32_t> fallback_rows;   // rows whose diagonal block is not SPD
  std::vector<Mat3> fallback_excess;         // their A_ii − ω D̃_i
  std::vector<std::vector<Vec3>> history;    // previous steps' Δv per particle (mm/s),
                                             // newest first, warm_start_history of them
  int warm_steps = 0;                        // consecutive implicit steps stored
  std::vector<std::vector<Vec3>> basis, abasis;   // projected warm start: orthonormal basis
                                                  // of the history and A·basis (solver order)
  std::int64_t warm_step = -2;               // World::step_count() at the last solve
  std::vector<Vec3> b, x, r, dir, q, s, t;  // CG work vectors (solver order)
  // SOR-preconditioned CG (sor_kernels.h layout): blocks row-major, vectors 4 doubles a row.
  std::vector<double> sor_blocks, sor_dinv;
  std::vector<double> x4, rho4, sigma4, p4, s4, g4, t4, q4;

  /// Builds the pattern if the models, the particle count or the fixed set changed.
  void ensure_pattern(const World& world);
  /// Sizes the warm-start history to @p depth steps (the stored Δv survive a change of
  /// length, newest first).
  void ensure_history(const World& world, int depth);
  /// Refills values with K at the current positions.
  void assemble_stiffness(const World& world);
  /// b = dt (f − dt K v), then K → A = M' + ak K in place, M' = (1 + dt α) M,
  /// ak = dt β + dt². Returns ‖b‖². Forces must be current.
  double assemble_system(const World& world, double dt_s);
  /// The preconditioner's inverse diagonal blocks (Jacobi's, or SSOR's D̃⁻¹).
  void build_preconditioner(const World& world, double dt_s, bool sgs, double omega);
  /// Sets x to the start of CG and r = b − A x; returns ‖r‖².
  double warm_start(const ImplicitEulerOptions& opts);
  /// The projected warm start; false if there is no usable history.
  bool projected_start(const ImplicitEulerOptions& opts, double& rr);
  /// Jacobi-preconditioned CG from x; returns the iterations, updates ‖r‖² in @p rr.
  int solve_jacobi(const ImplicitEulerOptions& opts, double target, double& rr);
  /// SSOR-preconditioned CG (Eisenstat's trick) from x; likewise.
  int solve_ssor(const ImplicitEulerOptions& opts, double omega, double target, double& rr);
  /// v += Δv, x += dt v for the free particles, and Δv into the history.
  void apply(World& world, double dt_s, int depth);

  /// out = S y for the symmetric matrix S whose upper block triangle is in values.
  void sym_product(const std::vector<Vec3>& y, std::vector<Vec3>& out) const;
  [[nodiscard]] double mass_term(const World& world, double dt_s, std::size_t i) const {
    const double am = 1.0 + dt_s * world.external().damping.mass_per_s;
    return am * kKgMmPerS2ToNewton * world.particles().masses()[static_cast<std::size_t>(particle_of[i])];
  }
};

namespace {
std::size_t slot(std::int32_t k) { return static_cast<std::size_t>(k); }
}  // namespace

// ---- pattern and history -----------------------------------------------------------------

void ImplicitEuler::Solver::ensure_pattern(const World& world) {
  const auto& p = world.particles();
  const std::size_t n = p.size();
  bool same = valid && model_revision == world.model_revision() && particle_count == n && fixed.size() == n;
  for (std::size_t i = 0; same && i < n; ++i) same = (fixed[i] != 0) == p.fixed(i);
  if (same) return;
  model_revision = world.model_revision();
  particle_count = n;
  fixed.resize(n);
  for (std::size_t i = 0; i < n; ++i) fixed[i] = p.fixed(i) ? 1 : 0;
  const auto models = world.models();
  std::vector<std::vector<BlockIndex>> patterns(models.size());
  // Graph of the free particles coupled by some model's stiffness.
  std::vector<std::vector<std::int32_t>> adj(n);
  for (std::size_t m = 0; m < models.size(); ++m) {
    patterns[m] = models[m]->stiffness_pattern();
    for (const auto& blk : patterns[m]) {
      if (blk.row < 0 || blk.col < 0 || static_cast<std::size_t>(blk.row) >= n ||
          static_cast<std::size_t>(blk.col) >= n)
        throw InvalidInput("implicit Euler: a force model refers to a particle that does not exist");
      const auto rw = static_cast<std::size_t>(blk.row), c = static_cast<std::size_t>(blk.col);
      if (rw != c && !fixed[rw] && !fixed[c]) {
        adj[rw].push_back(blk.col);
        adj[c].push_back(blk.row);
      }
    }
  }
  for (auto& a : adj) {
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
  }
  // Solver order: the free particles in particle order. (Tried: reverse Cuthill–McKee, which
  // makes the Gauss–Seidel sweeps run in diagonal wavefronts: 10 % more CG iterations on the
  // benchmark beam than any lexicographic order of its vertices.)
  particle_of.clear();
  std::vector<std::int32_t> solver_of(n, -1);
  for (std::size_t i = 0; i < n; ++i)
    if (!fixed[i]) {
      solver_of[i] = static_cast<std::int32_t>(particle_of.size());
      particle_of.push_back(static_cast<std::int32_t>(i));
    }
  const std::size_t m = particle_of.size();
  // Upper block triangle, rows in solver order, diagonal first.
  row_offset.assign(m + 1, 0);
  col.clear();
  std::vector<std::int32_t> row;
  for (std::size_t si = 0; si < m; ++si) {
    row.assign(1, static_cast<std::int32_t>(si));
    for (auto c : adj[static_cast<std::size_t>(particle_of[si])]) {
      const auto sc = solver_of[static_cast<std::size_t>(c)];
      if (sc > static_cast<std::int32_t>(si)) row.push_back(sc);
    }
    std::sort(row.begin(), row.end());
    col.insert(col.end(), row.begin(), row.end());
    row_offset[si + 1] = static_cast<std::int32_t>(col.size());
  }
  model_slots.assign(models.size(), {});
  for (std::size_t mi = 0; mi < models.size(); ++mi) {
    auto& slots = model_slots[mi];
    slots.resize(patterns[mi].size());
    for (std::size_t k = 0; k < patterns[mi].size(); ++k) {
      const auto& blk = patterns[mi][k];
      const auto sr = solver_of[static_cast<std::size_t>(blk.row)];
      const auto sc = solver_of[static_cast<std::size_t>(blk.col)];
      // Fixed particle, or lower triangle (its transpose, block (col, row), is stored).
      if (sr < 0 || sc < 0 || sc < sr) {
        slots[k] = -1;
        continue;
      }
      const auto first = col.begin() + row_offset[static_cast<std::size_t>(sr)];
      const auto last = col.begin() + row_offset[static_cast<std::size_t>(sr) + 1];
      slots[k] = static_cast<std::int32_t>(std::lower_bound(first, last, sc) - col.begin());
    }
  }
  values.assign(col.size(), Mat3::Zero());
  dinv.assign(m, Mat3::Zero());
  for (auto& h : history)
    if (h.size() != n) h.assign(n, Vec3::Zero());
  for (auto& w : basis) w.assign(m, Vec3::Zero());
  for (auto& w : abasis) w.assign(m, Vec3::Zero());
  warm_steps = 0;
  for (auto* v : {&b, &x, &r, &dir, &q, &s, &t}) v->assign(m, Vec3::Zero());
  for (auto* v : {&x4, &rho4, &sigma4, &p4, &s4, &g4, &t4, &q4}) v->assign(4 * m, 0.0);
  sor_blocks.assign(9 * col.size() + 3, 0.0);
  sor_dinv.assign(9 * m + 3, 0.0);
  valid = true;
}

void ImplicitEuler::Solver::ensure_history(const World& world, int depth_steps) {
  const auto depth = static_cast<std::size_t>(depth_steps);
  const std::size_t n = world.particles().size();
  if (history.size() != depth) {
    history.resize(depth);
    warm_steps = std::min(warm_steps, depth_steps);
  }
  for (auto& h : history)
    if (h.size() != n) h.assign(n, Vec3::Zero());
  const std::size_t m = particle_of.size();
  basis.resize(depth);
  abasis.resize(depth);
  for (auto* set : {&basis, &abasis})
    for (auto& w : *set)
      if (w.size() != m) w.assign(m, Vec3::Zero());
}

// ---- assembly ----------------------------------------------------------------------------

void ImplicitEuler::Solver::assemble_stiffness(const World& world) {
  std::fill(values.begin(), values.end(), Mat3::Zero());
  const auto models = world.models();
  for (std::size_t m = 0; m < models.size(); ++m)
    if (!model_slots[m].empty())
      models[m]->add_stiffness_to(world.particles(), model_slots[m], values, world.threaded());
}

void ImplicitEuler::Solver::sym_product(const std::vector<Vec3>& y, std::vector<Vec3>& out) const {
  std::fill(out.begin(), out.end(), Vec3::Zero());
  const std::size_t m = particle_of.size();
  for (std::size_t i = 0; i < m; ++i) {
    const Vec3 yi = y[i];
    Vec3 acc = values[slot(row_offset[i])] * yi;
    for (auto k = row_offset[i] + 1; k < row_offset[i + 1]; ++k) {
      const auto j = static_cast<std::size_t>(col[slot(k)]);
      acc.noalias() += values[slot(k)] * y[j];
      out[j].noalias() += values[slot(k)].transpose() * yi;
    }
    out[i] += acc;
  }
}

double ImplicitEuler::Solver::assemble_system(const World& world, double dt_s) {
  const auto& p = world.particles();
  const auto& f = p.forces();
  const auto& v = p.velocities();
  const auto& damping = world.external().damping;
  const double ak = dt_s * damping.stiffness_s + dt_s * dt_s;
  const std::size_t m = particle_of.size();
  // b = dt (f − dt K v).
  for (std::size_t i = 0; i < m; ++i) t[i] = v[static_cast<std::size_t>(particle_of[i])];
  sym_product(t, q);
  double bb = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    b[i] = dt_s * (f[static_cast<std::size_t>(particle_of[i])] - dt_s * q[i]);
    bb += b[i].squaredNorm();
  }
  // K → A = M' + ak K in place.
  for (std::size_t i = 0; i < m; ++i) {
    for (auto k = row_offset[i]; k < row_offset[i + 1]; ++k) values[slot(k)] *= ak;
    values[slot(row_offset[i])].diagonal().array() += mass_term(world, dt_s, i);
  }
  return bb;
}

void ImplicitEuler::Solver::build_preconditioner(const World& world, double dt_s, bool sgs, double omega) {
  // Jacobi: the inverse diagonal of A. Gauss–Seidel: D̃ = A_ii / ω, or the Jacobi diagonal / ω
  // where A_ii is not positive definite (the preconditioner stays symmetric positive definite
  // either way).
  fallback_rows.clear();
  fallback_excess.clear();
  const std::size_t m = particle_of.size();
  for (std::size_t i = 0; i < m; ++i) {
    const Mat3& a = values[slot(row_offset[i])];
    auto& di = dinv[i];
    if (sgs) {
      const Eigen::LLT<Mat3> llt(a);
      if (llt.info() == Eigen::Success) {
        di = omega * llt.solve(Mat3::Identity());
        continue;
      }
    }
    const double mt = mass_term(world, dt_s, i);
    Vec3 dd;
    for (int c = 0; c < 3; ++c) dd[c] = a(c, c) > 0.0 ? a(c, c) : (mt > 0.0 ? mt : 1.0);
    di = Mat3(dd.cwiseInverse().asDiagonal());
    if (sgs) {
      di *= omega;
      fallback_rows.push_back(static_cast<std::int32_t>(i));
      fallback_excess.push_back(a - Mat3(dd.asDiagonal()));
    }
  }
}

// ---- warm start --------------------------------------------------------------------------

bool ImplicitEuler::Solver::projected_start(const ImplicitEulerOptions& opts, double& rr) {
  // x₀ = W y, the Galerkin (A-norm best) approximation of Δv in the span of the last steps' Δv
  // — W an orthonormal basis of that span (modified Gram–Schmidt; a vector that adds less than
  // 1e-6 of its norm is dropped), (Wᵀ A W) y = Wᵀ b — and r₀ = b − (A W) y. This includes the
  // linear extrapolation 2 Δvₙ₋₁ − Δvₙ₋₂ and is never worse than it in the A-norm of the
  // error. Cost: one product with A per basis vector.
  const std::size_t m = particle_of.size();
  const int depth = std::min(warm_steps, opts.warm_start_history);
  int k = 0;
  for (int h = 0; h < depth; ++h) {
    auto& w = basis[static_cast<std::size_t>(k)];
    const auto& dv = history[static_cast<std::size_t>(h)];
    double n0 = 0.0;
    for (std::size_t i = 0; i < m; ++i) {
      w[i] = dv[static_cast<std::size_t>(particle_of[i])];
      n0 += w[i].squaredNorm();
    }
    for (int j = 0; j < k; ++j) {
      const auto& u = basis[static_cast<std::size_t>(j)];
      double d = 0.0;
      for (std::size_t i = 0; i < m; ++i) d += u[i].dot(w[i]);
      for (std::size_t i = 0; i < m; ++i) w[i] -= d * u[i];
    }
    double n1 = 0.0;
    for (std::size_t i = 0; i < m; ++i) n1 += w[i].squaredNorm();
    if (!(n1 > 1e-12 * n0)) continue;
    const double inv = 1.0 / std::sqrt(n1);
    for (std::size_t i = 0; i < m; ++i) w[i] *= inv;
    ++k;
  }
  if (k == 0) return false;
  Eigen::MatrixXd g(k, k);
  Eigen::VectorXd c(k);
  for (int j = 0; j < k; ++j) {
    const auto& w = basis[static_cast<std::size_t>(j)];
    auto& aw = abasis[static_cast<std::size_t>(j)];
    sym_product(w, aw);
    for (int l = 0; l <= j; ++l) {
      const auto& u = basis[static_cast<std::size_t>(l)];
      double d = 0.0;
      for (std::size_t i = 0; i < m; ++i) d += u[i].dot(aw[i]);
      g(l, j) = g(j, l) = d;
    }
    double d = 0.0;
    for (std::size_t i = 0; i < m; ++i) d += w[i].dot(b[i]);
    c[j] = d;
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(g);
  if (llt.info() != Eigen::Success) return false;   // A not positive definite on the span
  const Eigen::VectorXd y = llt.solve(c);
  rr = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    Vec3 xi = Vec3::Zero(), ri = b[i];
    for (int j = 0; j < k; ++j) {
      xi += y[j] * basis[static_cast<std::size_t>(j)][i];
      ri -= y[j] * abasis[static_cast<std::size_t>(j)][i];
    }
    x[i] = xi;
    r[i] = ri;
    rr += ri.squaredNorm();
  }
  return true;
}

double ImplicitEuler::Solver::warm_start(const ImplicitEulerOptions& opts) {
  const std::size_t m = particle_of.size();
  const bool warm = opts.warm_start;
  double rr = 0.0;
  if (warm && opts.warm_start_extrapolation && warm_steps >= 1 && projected_start(opts, rr)) return rr;
  // Plain warm start from the last Δv (or zero).
  for (std::size_t i = 0; i < m; ++i)
    x[i] = warm ? history[0][static_cast<std::size_t>(particle_of[i])] : Vec3::Zero();
  sym_product(x, q);
  rr = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    r[i] = b[i] - q[i];
    rr += r[i].squaredNorm();
  }
  return rr;
}

// ---- conjugate gradients -----------------------------------------------------------------

int ImplicitEuler::Solver::solve_jacobi(const ImplicitEulerOptions& opts, double target, double& rr) {
  // Preconditioned conjugate gradients (Shewchuk, "An Introduction to the Conjugate Gradient
  // Method Without the Agonizing Pain", 1994, §B3).
  const std::size_t m = particle_of.size();
  auto& z = s;
  auto& d = dir;
  int it = 0;
  double rz = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    z[i].noalias() = dinv[i] * r[i];
    rz += r[i].dot(z[i]);
  }
  d = z;
  while (it < opts.cg_max_iterations) {
    sym_product(d, q);
    double dq = 0.0;
    for (std::size_t i = 0; i < m; ++i) dq += d[i].dot(q[i]);
    if (!(dq > 0.0)) {
      // Not positive definite along d: keep the progress made; never re-apply a stale warm
      // start.
      if (it == 0) std::fill(x.begin(), x.end(), Vec3::Zero());
      break;
    }
    const double alpha = rz / dq;
    rr = 0.0;
    double rz_new = 0.0;
    for (std::size_t i = 0; i < m; ++i) {
      x[i] += alpha * d[i];
      r[i] -= alpha * q[i];
      rr += r[i].squaredNorm();
      z[i].noalias() = dinv[i] * r[i];
      rz_new += r[i].dot(z[i]);
    }
    ++it;
    if (rr <= target) break;
    const double beta = rz_new / rz;
    rz = rz_new;
    for (std::size_t i = 0; i < m; ++i) d[i] = z[i] + beta * d[i];
  }
  return it;
}

int ImplicitEuler::Solver::solve_ssor(const ImplicitEulerOptions& opts, double omega, double target,
                                      double& rr) {
  // Symmetric Gauss–Seidel (SSOR) preconditioner M = P D̃⁻¹ Pᵀ, P = D̃ + L, applied with
  // Eisenstat's trick (Eisenstat, "Efficient Implementation of a Class of Preconditioned
  // Conjugate Gradient Methods", SIAM J. Sci. Stat. Comput. 2, 1981): with A = P + Pᵀ + E,
  // E = A_diag − 2 D̃, CG on Â = W⁻ᵀ A W⁻¹ (W = C⁻¹ Pᵀ, D̃ = C Cᵀ; the same iterates as PCG
  // with M) needs per iteration one backward solve t = P⁻ᵀ p and one forward solve with P —
  // one pass over the stored upper triangle in all, instead of a product with A plus two
  // sweeps. Vectors are kept in unscaled form: ρ = P⁻¹ r (so r = P ρ), σ = D̃ ρ, p = C p̂;
  // Â p̂ = Cᵀ q with q = t + P⁻¹ (p + E t), and x += α t. Blocks and D̃⁻¹ row-major for the
  // kernels (sor_kernels.h), vectors padded to 4.
  const std::size_t m = particle_of.size();
  for (std::size_t k = 0; k < col.size(); ++k)
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(sor_blocks.data() + 9 * k) = values[k];
  for (std::size_t i = 0; i < m; ++i)
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(sor_dinv.data() + 9 * i) = dinv[i];
  const detail::SorMatrix sor{m, row_offset.data(), col.data(), sor_blocks.data(), sor_dinv.data()};
  double* rho = rho4.data();
  double* sigma = sigma4.data();
  double* pd = p4.data();
  double* sv = s4.data();
  double* g = g4.data();
  double* tv = t4.data();
  double* qv = q4.data();
  double* xv = x4.data();
  const std::size_t m4 = 4 * m;
  auto row3 = [](double* vec, std::size_t i) { return Eigen::Map<Vec3>(vec + 4 * i); };
  // ‖r‖² with r = P ρ = σ + L ρ (the recursive residual of PCG); lr scratch in r.
  auto residual2 = [&]() {
    auto& lr = r;
    std::fill(lr.begin(), lr.end(), Vec3::Zero());
    double sum = 0.0;
    for (std::size_t i = 0; i < m; ++i) {
      const Vec3 rhoi = row3(rho, i);
      sum += (row3(sigma, i) + lr[i]).squaredNorm();
      for (auto k = row_offset[i] + 1; k < row_offset[i + 1]; ++k)
        lr[static_cast<std::size_t>(col[slot(k)])].noalias() += values[slot(k)].transpose() * rhoi;
    }
    return sum;
  };
  int it = 0;
  std::fill(xv, xv + m4, 0.0);
  for (std::size_t i = 0; i < m; ++i) {
    row3(g, i) = r[i];
    g[4 * i + 3] = 0.0;
  }
  detail::sor_forward(sor, g, rho);   // ρ = P⁻¹ r, g = σ = D̃ ρ
  std::copy(g, g + m4, sigma);
  std::fill(pd, pd + m4, 0.0);
  double gamma = 0.0;
  for (std::size_t k = 0; k < m4; ++k) gamma += rho[k] * sigma[k];
  // ‖r‖² / ρ·σ, to decide when the true residual is worth computing.
  double ratio = rr / gamma;
  double beta = 0.0;
  while (it < opts.cg_max_iterations) {
    // Backward solve Pᵀ t = p (s = D̃ t) with the direction update p = σ + β p fused in, and
    // g = p + E t for the forward solve (E t = (ω − 2) s, plus the correction of rows whose
    // diagonal block fell back to Jacobi's).
    detail::sor_backward(sor, sigma, beta, omega - 2.0, pd, sv, tv, g);
    for (std::size_t fr = 0; fr < fallback_rows.size(); ++fr) {
      const auto i = static_cast<std::size_t>(fallback_rows[fr]);
      row3(g, i) += fallback_excess[fr] * Vec3(row3(tv, i));
    }
    detail::sor_forward(sor, g, qv);   // q = P⁻¹ (p + E t), g = D̃ q
    const double pq = detail::sor_add_dot(m, qv, tv, pd);
    if (!(pq > 0.0)) {
      // Not positive definite along p: keep the progress made; never re-apply a stale warm
      // start.
      if (it == 0) std::fill(x.begin(), x.end(), Vec3::Zero());
      break;
    }
    const double alpha = gamma / pq;
    const double gamma_new = detail::sor_update(m, alpha, tv, qv, sv, g, xv, rho, sigma);
    ++it;
    if (ratio * gamma_new <= target || it == opts.cg_max_iterations) {
      rr = residual2();
      ratio = rr / gamma_new;
      if (rr <= target) break;
    }
    beta = gamma_new / gamma;
    gamma = gamma_new;
  }
  for (std::size_t i = 0; i < m; ++i) x[i] += row3(xv, i);
  return it;
}

// ---- update ------------------------------------------------------------------------------

void ImplicitEuler::Solver::apply(World& world, double dt_s, int depth) {
  auto& p = world.particles();
  auto& v = p.velocities();
  auto& pos = p.positions();
  std::rotate(history.begin(), history.end() - 1, history.end());   // oldest becomes newest
  warm_steps = std::min(warm_steps + 1, depth);
  std::fill(history[0].begin(), history[0].end(), Vec3::Zero());
  for (std::size_t i = 0; i < particle_of.size(); ++i) {
    const auto pi = static_cast<std::size_t>(particle_of[i]);
    history[0][pi] = x[i];
    v[pi] += x[i];
    pos[pi] += dt_s * v[pi];
  }
}

// ---- the scheme --------------------------------------------------------------------------

ImplicitEuler::ImplicitEuler(const ImplicitEulerOptions& options)
    : m_options(options), m_solver(std::make_unique<Solver>()) {}

ImplicitEuler::~ImplicitEuler() = default;

void ImplicitEuler::step(World& world, double dt_s) {
  const auto& opts = m_options;
  const double omega = opts.sgs_relaxation;
  const bool sgs = opts.preconditioner == CgPreconditioner::SymmetricGaussSeidel;
  if (sgs && !(omega > 0.0 && omega < 2.0))
    throw InvalidInput("implicit Euler: the Gauss–Seidel relaxation must be in (0, 2), got " +
                       std::to_string(omega));
  if (opts.warm_start_history < 1 || opts.warm_start_history > kMaxWarmStartHistory)
    throw InvalidInput("implicit Euler: the warm-start history must hold 1 to " +
                       std::to_string(kMaxWarmStartHistory) + " steps, got " +
                       std::to_string(opts.warm_start_history));
  auto& s = *m_solver;
  s.ensure_pattern(world);
  s.ensure_history(world, opts.warm_start_history);

  s.assemble_stiffness(world);
  world.compute_forces();   // f(x, v), includes damping −C v
  const double bb = s.assemble_system(world, dt_s);
  s.build_preconditioner(world, dt_s, sgs, omega);

  // Use the history only over consecutive implicit steps (another scheme may have run
  // between).
  if (world.step_count() != s.warm_step + 1) s.warm_steps = 0;
  s.warm_step = world.step_count();
  double rr = s.warm_start(opts);
  const double bnorm = std::sqrt(bb);
  const double target = opts.cg_tolerance * opts.cg_tolerance * bb;
  int it = 0;
  if (bnorm > 0.0 && rr > target && opts.cg_max_iterations > 0)
    it = sgs ? s.solve_ssor(opts, omega, target, rr) : s.solve_jacobi(opts, target, rr);
  auto& stats = world.step_stats();
  stats.cg_iterations = it;
  stats.cg_relative_residual = bnorm > 0.0 ? std::sqrt(rr) / bnorm : 0.0;
  s.apply(world, dt_s, opts.warm_start_history);
}

}  // namespace ido::sim
