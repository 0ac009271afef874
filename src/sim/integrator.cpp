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
  std::vector<std::vector<std::int32_t>> rows(n);
  for (std::size_t i = 0; i < n; ++i)
    if (!fixed[i]) rows[i].push_back(static_cast<std::int32_t>(i));
  for (std::size_t m = 0; m < models.size(); ++m) {
    patterns[m] = models[m]->stiffness_pattern();
    for (const auto& b : patterns[m]) {
      if (b.row < 0 || b.col < 0 || static_cast<std::size_t>(b.row) >= n ||
          static_cast<std::size_t>(b.col) >= n)
        throw InvalidInput("implicit Euler: a force model refers to a particle that does not exist");
      if (!fixed[static_cast<std::size_t>(b.row)] && !fixed[static_cast<std::size_t>(b.col)])
        rows[static_cast<std::size_t>(b.row)].push_back(b.col);
    }
  }
  row_offset.assign(n + 1, 0);
  col.clear();
  diag_slot.assign(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    auto& r = rows[i];
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
    row_offset[i + 1] = row_offset[i] + static_cast<std::int32_t>(r.size());
    for (auto c : r) {
      if (static_cast<std::size_t>(c) == i) diag_slot[i] = static_cast<std::int32_t>(col.size());
      col.push_back(c);
    }
  }
  model_slots.assign(models.size(), {});
  for (std::size_t m = 0; m < models.size(); ++m) {
    auto& slots = model_slots[m];
    slots.resize(patterns[m].size());
    for (std::size_t k = 0; k < patterns[m].size(); ++k) {
      const auto& b = patterns[m][k];
      const auto r = static_cast<std::size_t>(b.row);
      if (fixed[r] || fixed[static_cast<std::size_t>(b.col)]) {
        slots[k] = -1;
        continue;
      }
      const auto first = col.begin() + row_offset[r], last = col.begin() + row_offset[r + 1];
      slots[k] = static_cast<std::int32_t>(std::lower_bound(first, last, b.col) - col.begin());
    }
  }
  values.assign(col.size(), Mat3::Zero());
  precond.assign(n, Mat3::Zero());
  if (warm_dv.size() != n) warm_dv.assign(n, Vec3::Zero());
  for (auto* v : {&b, &r, &z, &d, &q, &dv, &kv}) v->assign(n, Vec3::Zero());
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
  const std::size_t n = p.size();
  const auto& opts = world.implicit_options();
  const auto& damping = world.external().damping;
  const bool threaded = world.threaded();

  cache.assemble(world);
  world.compute_forces();  // f(x, v), includes damping −C v
  const auto& f = p.forces();
  auto& v = p.velocities();
  auto& x = p.positions();
  const auto& mass = p.masses();

  // System (M' + ak K) Δv = dt (f − dt K v), M' = (1 + dt α) M, ak = dt β + dt².
  const double am = 1.0 + dt_s * damping.mass_per_s;
  const double ak = dt_s * damping.stiffness_s + dt_s * dt_s;
  const auto& row_offset = cache.row_offset;
  const auto& col = cache.col;
  const auto& values = cache.values;
  const auto& fixed = cache.fixed;
  auto mass_term = [&](std::size_t i) { return am * kKgMmPerS2ToNewton * mass[i]; };
  // (K y)_i over the free block; y is zero on fixed particles, whose rows are empty.
  auto k_row = [&](const std::vector<Vec3>& y, std::int32_t begin, std::int32_t end) {
    Vec3 s = Vec3::Zero();
    for (auto k = begin; k < end; ++k)
      s.noalias() += values[static_cast<std::size_t>(k)] * y[static_cast<std::size_t>(col[static_cast<std::size_t>(k)])];
    return s;
  };
  // out = A y; returns y·out (serial sum in index order, so threaded runs give the same bits).
  auto a_times = [&](const std::vector<Vec3>& y, std::vector<Vec3>& out) {
    auto row = [&](std::size_t i) {
      out[i] = fixed[i] ? Vec3::Zero()
                        : Vec3(mass_term(i) * y[i] + ak * k_row(y, row_offset[i], row_offset[i + 1]));
    };
    double dot = 0.0;
    if (threaded) {
      parallel_for(n, row, true, 256);
      for (std::size_t i = 0; i < n; ++i) dot += y[i].dot(out[i]);
    } else {
      for (std::size_t i = 0; i < n; ++i) {
        row(i);
        dot += y[i].dot(out[i]);
      }
    }
    return dot;
  };

  // Preconditioner blocks. Jacobi: inverse diagonal of A. Gauss–Seidel: inverse 3×3 diagonal
  // block of A, or the Jacobi diagonal where that block is not positive definite (the
  // preconditioner stays symmetric positive definite either way).
  const bool sgs = opts.preconditioner == CgPreconditioner::SymmetricGaussSeidel;
  for (std::size_t i = 0; i < n; ++i) {
    auto& pc = cache.precond[i];
    if (fixed[i]) {
      pc.setZero();
      continue;
    }
    const double mterm = mass_term(i);
    const Mat3 dblock = mterm * Mat3::Identity() + ak * values[static_cast<std::size_t>(cache.diag_slot[i])];
    if (sgs) {
      const Eigen::LLT<Mat3> llt(dblock);
      if (llt.info() == Eigen::Success) {
        pc = llt.solve(Mat3::Identity());
        continue;
      }
    }
    pc.setZero();
    for (int c = 0; c < 3; ++c) pc(c, c) = 1.0 / (dblock(c, c) > 0.0 ? dblock(c, c) : mterm);
  }
  auto& r = cache.r;
  auto& z = cache.z;
  // z = P⁻¹ r; returns r·z.
  auto precondition = [&]() {
    double rz = 0.0;
    if (!sgs) {
      for (std::size_t i = 0; i < n; ++i) {
        z[i].noalias() = cache.precond[i] * r[i];
        rz += r[i].dot(z[i]);
      }
      return rz;
    }
    // Forward sweep (D + L) y = r, then backward (D + Lᵀ) z = D y, in place in z.
    for (std::size_t i = 0; i < n; ++i) {
      if (fixed[i]) continue;
      const Vec3 s = r[i] - ak * k_row(z, row_offset[i], cache.diag_slot[i]);
      z[i].noalias() = cache.precond[i] * s;
    }
    for (std::size_t i = n; i-- > 0;) {
      if (fixed[i]) continue;
      const Vec3 s = ak * k_row(z, cache.diag_slot[i] + 1, row_offset[i + 1]);
      z[i].noalias() -= cache.precond[i] * s;
      rz += r[i].dot(z[i]);
    }
    return rz;
  };

  // b = dt (f − dt K v) on free particles.
  auto& b = cache.b;
  auto& kv = cache.kv;
  auto& vfree = cache.d;   // scratch: v with fixed particles zeroed
  for (std::size_t i = 0; i < n; ++i) vfree[i] = fixed[i] ? Vec3::Zero() : v[i];
  parallel_for(
      n, [&](std::size_t i) { kv[i] = k_row(vfree, row_offset[i], row_offset[i + 1]); }, threaded, 256);
  double bb = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    b[i] = fixed[i] ? Vec3::Zero() : Vec3(dt_s * (f[i] - dt_s * kv[i]));
    bb += b[i].squaredNorm();
  }

  // Preconditioned conjugate gradients (Shewchuk, "An Introduction to the Conjugate Gradient
  // Method Without the Agonizing Pain", 1994, §B3).
  auto& dv = cache.dv;
  auto& d = cache.d;
  auto& q = cache.q;
  const bool warm = opts.warm_start && cache.warm_dv.size() == n;
  for (std::size_t i = 0; i < n; ++i) dv[i] = (warm && !fixed[i]) ? cache.warm_dv[i] : Vec3::Zero();
  (void)a_times(dv, q);
  double rr = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    r[i] = b[i] - q[i];
    rr += r[i].squaredNorm();
  }
  const double bnorm = std::sqrt(bb);
  int it = 0;
  double rnorm = std::sqrt(rr);
  if (bnorm > 0.0 && rnorm > opts.cg_tolerance * bnorm) {
    std::fill(z.begin(), z.end(), Vec3::Zero());
    double rz = precondition();
    d = z;
    while (it < opts.cg_max_iterations) {
      const double dq = a_times(d, q);
      if (!(dq > 0.0)) {
        // Not positive definite along d: keep the progress made; never re-apply a stale
        // warm start.
        if (it == 0) std::fill(dv.begin(), dv.end(), Vec3::Zero());
        break;
      }
      const double alpha = rz / dq;
      rr = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        dv[i] += alpha * d[i];
        r[i] -= alpha * q[i];
        rr += r[i].squaredNorm();
      }
      ++it;
      rnorm = std::sqrt(rr);
      if (rnorm <= opts.cg_tolerance * bnorm) break;
      const double rz_new = precondition();
      const double beta = rz_new / rz;
      rz = rz_new;
      for (std::size_t i = 0; i < n; ++i) d[i] = z[i] + beta * d[i];
    }
  }
  auto& stats = world.step_stats();
  stats.cg_iterations = it;
  stats.cg_relative_residual = bnorm > 0.0 ? rnorm / bnorm : 0.0;
  cache.warm_dv = dv;
  for (std::size_t i = 0; i < n; ++i) {
    if (fixed[i]) continue;
    v[i] += dv[i];
    x[i] += dt_s * v[i];
  }
}

}  // namespace integrators
}  // namespace ido::sim
