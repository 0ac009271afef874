// SPDX-License-Identifier: Apache-2.0
#include "ido/sim/integrator.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Cholesky>

#include "ido/core/error.h"
#include "ido/core/parallel.h"
#include "ido/sim/units.h"
#include "ido/sim/world.h"
#include "implicit_cache.h"
#include "sor_kernels.h"

namespace ido::sim {

// ---- registry ----------------------------------------------------------------------------

IntegratorRegistry::IntegratorRegistry() {
  m_fns["explicit_euler"] = integrators::explicit_euler;
  m_fns["symplectic_euler"] = integrators::symplectic_euler;
  m_fns["velocity_verlet"] = integrators::velocity_verlet;
  m_fns["rk4"] = integrators::rk4;
  m_fns["implicit_euler"] = integrators::implicit_euler;
}

void IntegratorRegistry::add(const std::string& name, IntegratorFn fn) {
  if (name.empty()) throw InvalidInput("integrator registry: empty name");
  if (!fn) throw InvalidInput("integrator registry: empty function for '" + name + "'");
  m_fns[name] = std::move(fn);
}

bool IntegratorRegistry::contains(const std::string& name) const { return m_fns.count(name) != 0; }

const IntegratorFn& IntegratorRegistry::get(const std::string& name) const {
  const auto it = m_fns.find(name);
  if (it == m_fns.end()) {
    std::string known;
    for (const auto& [k, fn] : m_fns) known += (known.empty() ? "" : ", ") + k;
    throw InvalidInput("unknown integrator '" + name + "' (known: " + known + ")");
  }
  return it->second;
}

std::vector<std::string> IntegratorRegistry::names() const {
  std::vector<std::string> out;
  for (const auto& [k, fn] : m_fns) out.push_back(k);
  return out;
}

// ---- explicit schemes --------------------------------------------------------------------

namespace integrators {

void explicit_euler(World& world, double dt_s) {
  world.compute_forces();
  const auto a = world.accelerations();
  auto& p = world.particles();
  auto& x = p.positions();
  auto& v = p.velocities();
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (p.fixed(i)) continue;
    x[i] += dt_s * v[i];
    v[i] += dt_s * a[i];
  }
}

void symplectic_euler(World& world, double dt_s) {
  world.compute_forces();
  const auto a = world.accelerations();
  auto& p = world.particles();
  auto& x = p.positions();
  auto& v = p.velocities();
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (p.fixed(i)) continue;
    v[i] += dt_s * a[i];
    x[i] += dt_s * v[i];
  }
}

void velocity_verlet(World& world, double dt_s) {
  auto& p = world.particles();
  auto& x = p.positions();
  auto& v = p.velocities();
  world.compute_forces();
  auto a = world.accelerations();
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (p.fixed(i)) continue;
    v[i] += 0.5 * dt_s * a[i];
    x[i] += dt_s * v[i];
  }
  world.compute_forces();
  a = world.accelerations();
  for (std::size_t i = 0; i < x.size(); ++i)
    if (!p.fixed(i)) v[i] += 0.5 * dt_s * a[i];
}

void rk4(World& world, double dt_s) {
  auto& p = world.particles();
  auto& x = p.positions();
  auto& v = p.velocities();
  const std::size_t n = x.size();
  const std::vector<Vec3> x0 = x, v0 = v;
  std::vector<Vec3> kx[4], kv[4];
  const double c[4] = {0.0, 0.5, 0.5, 1.0};
  for (int s = 0; s < 4; ++s) {
    if (s > 0)
      for (std::size_t i = 0; i < n; ++i) {
        if (p.fixed(i)) continue;
        x[i] = x0[i] + c[s] * dt_s * kx[s - 1][i];
        v[i] = v0[i] + c[s] * dt_s * kv[s - 1][i];
      }
    world.compute_forces();
    kx[s] = v;
    kv[s] = world.accelerations();
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (p.fixed(i)) continue;
    x[i] = x0[i] + dt_s / 6.0 * (kx[0][i] + 2.0 * kx[1][i] + 2.0 * kx[2][i] + kx[3][i]);
    v[i] = v0[i] + dt_s / 6.0 * (kv[0][i] + 2.0 * kv[1][i] + 2.0 * kv[2][i] + kv[3][i]);
  }
}

}  // namespace integrators

// ---- implicit Euler ----------------------------------------------------------------------

void World::ImplicitCache::ensure(const World& world) {
  const auto& p = world.particles();
  const std::size_t n = p.size();
  bool same = valid && particle_count == n && fixed.size() == n;
  for (std::size_t i = 0; same && i < n; ++i) same = (fixed[i] != 0) == p.fixed(i);
  if (same) return;
  particle_count = n;
  fixed.resize(n);
  for (std::size_t i = 0; i < n; ++i) fixed[i] = p.fixed(i) ? 1 : 0;
  const auto models = world.models();
  std::vector<std::vector<BlockIndex>> patterns(models.size());
  // Graph of the free particles coupled by some model's stiffness.
  std::vector<std::vector<std::int32_t>> adj(n);
  for (std::size_t m = 0; m < models.size(); ++m) {
    patterns[m] = models[m]->stiffness_pattern();
    for (const auto& b : patterns[m]) {
      if (b.row < 0 || b.col < 0 || static_cast<std::size_t>(b.row) >= n ||
          static_cast<std::size_t>(b.col) >= n)
        throw InvalidInput("implicit Euler: a force model refers to a particle that does not exist");
      const auto r = static_cast<std::size_t>(b.row), c = static_cast<std::size_t>(b.col);
      if (r != c && !fixed[r] && !fixed[c]) {
        adj[r].push_back(b.col);
        adj[c].push_back(b.row);
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
  for (std::size_t s = 0; s < m; ++s) {
    row.assign(1, static_cast<std::int32_t>(s));
    for (auto c : adj[static_cast<std::size_t>(particle_of[s])]) {
      const auto sc = solver_of[static_cast<std::size_t>(c)];
      if (sc > static_cast<std::int32_t>(s)) row.push_back(sc);
    }
    std::sort(row.begin(), row.end());
    col.insert(col.end(), row.begin(), row.end());
    row_offset[s + 1] = static_cast<std::int32_t>(col.size());
  }
  model_slots.assign(models.size(), {});
  for (std::size_t mi = 0; mi < models.size(); ++mi) {
    auto& slots = model_slots[mi];
    slots.resize(patterns[mi].size());
    for (std::size_t k = 0; k < patterns[mi].size(); ++k) {
      const auto& b = patterns[mi][k];
      const auto sr = solver_of[static_cast<std::size_t>(b.row)];
      const auto sc = solver_of[static_cast<std::size_t>(b.col)];
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

void World::ImplicitCache::assemble(const World& world) {
  std::fill(values.begin(), values.end(), Mat3::Zero());
  const auto models = world.models();
  for (std::size_t m = 0; m < models.size(); ++m)
    if (!model_slots[m].empty())
      models[m]->add_stiffness_to(world.particles(), model_slots[m], values, world.threaded());
}

namespace integrators {

void implicit_euler(World& world, double dt_s) {
  auto& cache = world.implicit_cache();
  cache.ensure(world);
  auto& p = world.particles();
  const auto& opts = world.implicit_options();
  const auto& damping = world.external().damping;
  const double omega = opts.sgs_relaxation;
  const bool sgs = opts.preconditioner == CgPreconditioner::SymmetricGaussSeidel;
  if (sgs && !(omega > 0.0 && omega < 2.0))
    throw InvalidInput("implicit Euler: the Gauss–Seidel relaxation must be in (0, 2), got " +
                       std::to_string(omega));
  if (opts.warm_start_history < 1 || opts.warm_start_history > kMaxWarmStartHistory)
    throw InvalidInput("implicit Euler: the warm-start history must hold 1 to " +
                       std::to_string(kMaxWarmStartHistory) + " steps, got " +
                       std::to_string(opts.warm_start_history));
  {
    // History length (the stored Δv survive a change of length, newest first).
    const auto depth = static_cast<std::size_t>(opts.warm_start_history);
    const std::size_t n = p.size();
    if (cache.history.size() != depth) {
      cache.history.resize(depth);
      cache.warm_steps = std::min(cache.warm_steps, opts.warm_start_history);
    }
    for (auto& h : cache.history)
      if (h.size() != n) h.assign(n, Vec3::Zero());
    const std::size_t m = cache.particle_of.size();
    cache.basis.resize(depth);
    cache.abasis.resize(depth);
    for (auto* set : {&cache.basis, &cache.abasis})
      for (auto& w : *set)
        if (w.size() != m) w.assign(m, Vec3::Zero());
  }

  cache.assemble(world);
  world.compute_forces();  // f(x, v), includes damping −C v
  const auto& f = p.forces();
  auto& v = p.velocities();
  auto& pos = p.positions();
  const auto& mass = p.masses();

  // System (M' + ak K) Δv = dt (f − dt K v), M' = (1 + dt α) M, ak = dt β + dt², over the
  // free particles in solver order (cache.particle_of).
  const double am = 1.0 + dt_s * damping.mass_per_s;
  const double ak = dt_s * damping.stiffness_s + dt_s * dt_s;
  const std::size_t m = cache.particle_of.size();
  const auto& particle_of = cache.particle_of;
  const auto& row_offset = cache.row_offset;
  const auto& col = cache.col;
  auto& values = cache.values;
  auto mass_term = [&](std::size_t i) {
    return am * kKgMmPerS2ToNewton * mass[static_cast<std::size_t>(particle_of[i])];
  };
  auto slot = [](std::int32_t k) { return static_cast<std::size_t>(k); };
  // out = S y for the symmetric matrix S whose upper block triangle is in values.
  auto sym_product = [&](const std::vector<Vec3>& y, std::vector<Vec3>& out) {
    std::fill(out.begin(), out.end(), Vec3::Zero());
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
  };

  // b = dt (f − dt K v).
  auto& b = cache.b;
  auto& q = cache.q;
  auto& t = cache.t;
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
    values[slot(row_offset[i])].diagonal().array() += mass_term(i);
  }

  // Preconditioner diagonal blocks. Jacobi: the inverse diagonal of A. Gauss–Seidel: D̃ =
  // A_ii / ω, or the Jacobi diagonal / ω where A_ii is not positive definite (the
  // preconditioner stays symmetric positive definite either way).
  cache.fallback_rows.clear();
  cache.fallback_excess.clear();
  for (std::size_t i = 0; i < m; ++i) {
    const Mat3& a = values[slot(row_offset[i])];
    auto& di = cache.dinv[i];
    if (sgs) {
      const Eigen::LLT<Mat3> llt(a);
      if (llt.info() == Eigen::Success) {
        di = omega * llt.solve(Mat3::Identity());
        continue;
      }
    }
    Vec3 dd;
    for (int c = 0; c < 3; ++c) dd[c] = a(c, c) > 0.0 ? a(c, c) : (mass_term(i) > 0.0 ? mass_term(i) : 1.0);
    di = Mat3(dd.cwiseInverse().asDiagonal());
    if (sgs) {
      di *= omega;
      cache.fallback_rows.push_back(static_cast<std::int32_t>(i));
      cache.fallback_excess.push_back(a - Mat3(dd.asDiagonal()));
    }
  }

  // Preconditioned conjugate gradients (Shewchuk, "An Introduction to the Conjugate Gradient
  // Method Without the Agonizing Pain", 1994, §B3), warm-started from the previous steps' Δv.
  auto& x = cache.x;
  auto& r = cache.r;
  const bool warm = opts.warm_start;
  // Use the history only over consecutive implicit steps (another scheme may have run
  // between).
  if (world.step_count() != cache.warm_step + 1) cache.warm_steps = 0;
  cache.warm_step = world.step_count();
  double rr = 0.0;
  // Projected warm start: x₀ = W y, the Galerkin (A-norm best) approximation of Δv in the
  // span of the last steps' Δv — W an orthonormal basis of that span (modified Gram–Schmidt;
  // a vector that adds less than 1e-6 of its norm is dropped), (Wᵀ A W) y = Wᵀ b — and
  // r₀ = b − (A W) y. This includes the linear extrapolation 2 Δvₙ₋₁ − Δvₙ₋₂ and is never
  // worse than it in the A-norm of the error. Cost: one product with A per basis vector.
  auto projected_start = [&]() {
    const int depth = std::min(cache.warm_steps, opts.warm_start_history);
    int k = 0;
    for (int h = 0; h < depth; ++h) {
      auto& w = cache.basis[static_cast<std::size_t>(k)];
      const auto& dv = cache.history[static_cast<std::size_t>(h)];
      double n0 = 0.0;
      for (std::size_t i = 0; i < m; ++i) {
        w[i] = dv[static_cast<std::size_t>(particle_of[i])];
        n0 += w[i].squaredNorm();
      }
      for (int j = 0; j < k; ++j) {
        const auto& u = cache.basis[static_cast<std::size_t>(j)];
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
      const auto& w = cache.basis[static_cast<std::size_t>(j)];
      auto& aw = cache.abasis[static_cast<std::size_t>(j)];
      sym_product(w, aw);
      for (int l = 0; l <= j; ++l) {
        const auto& u = cache.basis[static_cast<std::size_t>(l)];
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
        xi += y[j] * cache.basis[static_cast<std::size_t>(j)][i];
        ri -= y[j] * cache.abasis[static_cast<std::size_t>(j)][i];
      }
      x[i] = xi;
      r[i] = ri;
      rr += ri.squaredNorm();
    }
    return true;
  };
  if (!(warm && opts.warm_start_extrapolation && cache.warm_steps >= 1 && projected_start())) {
    // Plain warm start from the last Δv (or zero).
    for (std::size_t i = 0; i < m; ++i)
      x[i] = warm ? cache.history[0][static_cast<std::size_t>(particle_of[i])] : Vec3::Zero();
    sym_product(x, q);
    rr = 0.0;
    for (std::size_t i = 0; i < m; ++i) {
      r[i] = b[i] - q[i];
      rr += r[i].squaredNorm();
    }
  }
  const double bnorm = std::sqrt(bb);
  const double target = opts.cg_tolerance * opts.cg_tolerance * bb;
  int it = 0;
  if (bnorm > 0.0 && rr > target && opts.cg_max_iterations > 0) {
    if (!sgs) {
      auto& z = cache.s;
      auto& d = cache.dir;
      double rz = 0.0;
      for (std::size_t i = 0; i < m; ++i) {
        z[i].noalias() = cache.dinv[i] * r[i];
        rz += r[i].dot(z[i]);
      }
      d = z;
      while (it < opts.cg_max_iterations) {
        sym_product(d, q);
        double dq = 0.0;
        for (std::size_t i = 0; i < m; ++i) dq += d[i].dot(q[i]);
        if (!(dq > 0.0)) {
          // Not positive definite along d: keep the progress made; never re-apply a stale
          // warm start.
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
          z[i].noalias() = cache.dinv[i] * r[i];
          rz_new += r[i].dot(z[i]);
        }
        ++it;
        if (rr <= target) break;
        const double beta = rz_new / rz;
        rz = rz_new;
        for (std::size_t i = 0; i < m; ++i) d[i] = z[i] + beta * d[i];
      }
    } else {
      // Symmetric Gauss–Seidel (SSOR) preconditioner M = P D̃⁻¹ Pᵀ, P = D̃ + L, applied with
      // Eisenstat's trick (Eisenstat, "Efficient Implementation of a Class of Preconditioned
      // Conjugate Gradient Methods", SIAM J. Sci. Stat. Comput. 2, 1981): with A = P + Pᵀ + E,
      // E = A_diag − 2 D̃, CG on Â = W⁻ᵀ A W⁻¹ (W = C⁻¹ Pᵀ, D̃ = C Cᵀ; the same iterates as
      // PCG with M) needs per iteration one backward solve t = P⁻ᵀ p and one forward solve
      // with P — one pass over the stored upper triangle in all, instead of a product with
      // A plus two sweeps. Vectors are kept in unscaled form: ρ = P⁻¹ r (so r = P ρ),
      // σ = D̃ ρ, p = C p̂; Â p̂ = Cᵀ q with q = t + P⁻¹ (p + E t), and x += α t.
      // Blocks and D̃⁻¹ row-major for the kernels (sor_kernels.h), vectors padded to 4.
      for (std::size_t k = 0; k < col.size(); ++k)
        Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(cache.sor_blocks.data() + 9 * k) = values[k];
      for (std::size_t i = 0; i < m; ++i)
        Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(cache.sor_dinv.data() + 9 * i) = cache.dinv[i];
      const detail::SorMatrix sor{m, row_offset.data(), col.data(), cache.sor_blocks.data(),
                                  cache.sor_dinv.data()};
      double* rho = cache.rho4.data();
      double* sigma = cache.sigma4.data();
      double* pd = cache.p4.data();
      double* s = cache.s4.data();
      double* g = cache.g4.data();
      double* t4 = cache.t4.data();
      double* q4 = cache.q4.data();
      double* x4 = cache.x4.data();
      const std::size_t m4 = 4 * m;
      auto row3 = [](double* vec, std::size_t i) { return Eigen::Map<Vec3>(vec + 4 * i); };
      // ‖r‖² with r = P ρ = σ + L ρ (the recursive residual of PCG); lr scratch in cache.r.
      auto residual2 = [&]() {
        auto& lr = cache.r;
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
      std::fill(x4, x4 + m4, 0.0);
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
        // Backward solve Pᵀ t = p (s = D̃ t) with the direction update p = σ + β p fused in,
        // and g = p + E t for the forward solve (E t = (ω − 2) s, plus the correction of rows
        // whose diagonal block fell back to Jacobi's).
        detail::sor_backward(sor, sigma, beta, omega - 2.0, pd, s, t4, g);
        for (std::size_t fr = 0; fr < cache.fallback_rows.size(); ++fr) {
          const auto i = static_cast<std::size_t>(cache.fallback_rows[fr]);
          row3(g, i) += cache.fallback_excess[fr] * Vec3(row3(t4, i));
        }
        detail::sor_forward(sor, g, q4);   // q = P⁻¹ (p + E t), g = D̃ q
        const double pq = detail::sor_add_dot(m, q4, t4, pd);
        if (!(pq > 0.0)) {
          // Not positive definite along p: keep the progress made; never re-apply a stale
          // warm start.
          if (it == 0) std::fill(x.begin(), x.end(), Vec3::Zero());
          break;
        }
        const double alpha = gamma / pq;
        const double gamma_new = detail::sor_update(m, alpha, t4, q4, s, g, x4, rho, sigma);
        ++it;
        if (ratio * gamma_new <= target || it == opts.cg_max_iterations) {
          rr = residual2();
          ratio = rr / gamma_new;
          if (rr <= target) break;
        }
        beta = gamma_new / gamma;
        gamma = gamma_new;
      }
      for (std::size_t i = 0; i < m; ++i) x[i] += row3(x4, i);
    }
  }
  auto& stats = world.step_stats();
  stats.cg_iterations = it;
  stats.cg_relative_residual = bnorm > 0.0 ? std::sqrt(rr) / bnorm : 0.0;
  auto& history = cache.history;
  std::rotate(history.begin(), history.end() - 1, history.end());   // oldest becomes newest
  cache.warm_steps = std::min(cache.warm_steps + 1, opts.warm_start_history);
  std::fill(history[0].begin(), history[0].end(), Vec3::Zero());
  for (std::size_t i = 0; i < m; ++i) {
    const auto pi = static_cast<std::size_t>(particle_of[i]);
    history[0][pi] = x[i];
    v[pi] += x[i];
    pos[pi] += dt_s * v[pi];
  }
}

}  // namespace integrators
}  // namespace ido::sim
