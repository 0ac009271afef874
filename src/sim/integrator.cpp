// SPDX-License-Identifier: Apache-2.0
#include "ido/sim/integrator.h"

#include <algorithm>
#include <cmath>
#include <string>

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
  if (valid && particle_count == p.size()) return;
  const std::size_t n = p.size();
  particle_count = n;
  std::vector<BlockIndex> all;
  model_first.clear();
  for (const auto& m : world.models()) {
    model_first.push_back(all.size());
    auto pat = m->stiffness_pattern();
    all.insert(all.end(), pat.begin(), pat.end());
  }
  model_first.push_back(all.size());
  std::vector<std::vector<std::int32_t>> rows(n);
  for (std::size_t i = 0; i < n; ++i) rows[i].push_back(static_cast<std::int32_t>(i));
  for (const auto& b : all) {
    if (b.row < 0 || b.col < 0 || static_cast<std::size_t>(b.row) >= n ||
        static_cast<std::size_t>(b.col) >= n)
      throw InvalidInput("implicit Euler: a force model refers to a particle that does not exist");
    rows[static_cast<std::size_t>(b.row)].push_back(b.col);
  }
  row_offset.assign(n + 1, 0);
  col.clear();
  diag_slot.assign(n, 0);
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
  std::vector<std::int32_t> slot_of(all.size());
  for (std::size_t k = 0; k < all.size(); ++k) {
    const auto r = static_cast<std::size_t>(all[k].row);
    const auto first = col.begin() + row_offset[r], last = col.begin() + row_offset[r + 1];
    slot_of[k] = static_cast<std::int32_t>(std::lower_bound(first, last, all[k].col) - col.begin());
  }
  // Contributions per slot (counting sort keeps block order within a slot).
  slot_offset.assign(col.size() + 1, 0);
  for (auto s : slot_of) ++slot_offset[static_cast<std::size_t>(s) + 1];
  for (std::size_t s = 0; s < col.size(); ++s) slot_offset[s + 1] += slot_offset[s];
  slot_sources.resize(all.size());
  std::vector<std::int32_t> fill(slot_offset.begin(), slot_offset.end() - 1);
  for (std::size_t k = 0; k < all.size(); ++k)
    slot_sources[static_cast<std::size_t>(fill[static_cast<std::size_t>(slot_of[k])]++)] =
        static_cast<std::int32_t>(k);
  model_blocks.assign(all.size(), Mat3::Zero());
  values.assign(col.size(), Mat3::Zero());
  if (warm_dv.size() != n) warm_dv.assign(n, Vec3::Zero());
  valid = true;
}

void World::ImplicitCache::assemble(const World& world) {
  const auto models = world.models();
  for (std::size_t m = 0; m < models.size(); ++m) {
    const std::size_t b = model_first[m], e = model_first[m + 1];
    if (e > b)
      models[m]->stiffness_blocks(world.particles(),
                                  std::span<Mat3>(model_blocks.data() + b, e - b), world.threaded());
  }
  parallel_for(
      values.size(),
      [&](std::size_t s) {
        Mat3 sum = Mat3::Zero();
        for (auto k = slot_offset[s]; k < slot_offset[s + 1]; ++k)
          sum += model_blocks[static_cast<std::size_t>(slot_sources[static_cast<std::size_t>(k)])];
        values[s] = sum;
      },
      world.threaded(), 4096);
}

namespace {

double dot(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double s = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) s += a[i].dot(b[i]);
  return s;
}

}  // namespace

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

  const double am = 1.0 + dt_s * damping.mass_per_s;         // × M'
  const double ak = dt_s * damping.stiffness_s + dt_s * dt_s; // × K
  std::vector<char> free(n);
  for (std::size_t i = 0; i < n; ++i) free[i] = p.fixed(i) ? 0 : 1;

  auto k_times = [&](const std::vector<Vec3>& y, std::vector<Vec3>& out) {
    parallel_for(
        n,
        [&](std::size_t i) {
          Vec3 s = Vec3::Zero();
          for (auto k = cache.row_offset[i]; k < cache.row_offset[i + 1]; ++k) {
            const auto c = static_cast<std::size_t>(cache.col[static_cast<std::size_t>(k)]);
            if (free[c]) s += cache.values[static_cast<std::size_t>(k)] * y[c];
          }
          out[i] = s;
        },
        threaded, 512);
  };
  auto a_times = [&](const std::vector<Vec3>& y, std::vector<Vec3>& out) {
    k_times(y, out);
    for (std::size_t i = 0; i < n; ++i)
      out[i] = free[i] ? Vec3(am * kKgMmPerS2ToNewton * mass[i] * y[i] + ak * out[i]) : y[i];
  };

  // b = dt (f − dt K v)
  std::vector<Vec3> kv(n), b(n);
  k_times(v, kv);
  for (std::size_t i = 0; i < n; ++i)
    b[i] = free[i] ? Vec3(dt_s * (f[i] - dt_s * kv[i])) : Vec3::Zero();
  std::vector<Vec3> inv_diag(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double mterm = am * kKgMmPerS2ToNewton * mass[i];
    const Mat3& kd = cache.values[static_cast<std::size_t>(cache.diag_slot[i])];
    for (int c = 0; c < 3; ++c) {
      const double d = mterm + ak * kd(c, c);
      inv_diag[i][c] = free[i] ? 1.0 / (d > 0.0 ? d : mterm) : 1.0;
    }
  }
  // Preconditioned conjugate gradients (Shewchuk, "An Introduction to the Conjugate Gradient
  // Method Without the Agonizing Pain", 1994, §B3).
  std::vector<Vec3> dv(n, Vec3::Zero());
  if (opts.warm_start && cache.warm_dv.size() == n)
    for (std::size_t i = 0; i < n; ++i) dv[i] = free[i] ? cache.warm_dv[i] : Vec3::Zero();
  std::vector<Vec3> r(n), z(n), d(n), q(n);
  a_times(dv, q);
  for (std::size_t i = 0; i < n; ++i) r[i] = b[i] - q[i];
  const double bnorm = std::sqrt(dot(b, b));
  int it = 0;
  double rnorm = std::sqrt(dot(r, r));
  if (bnorm > 0.0 && rnorm > opts.cg_tolerance * bnorm) {
    for (std::size_t i = 0; i < n; ++i) z[i] = inv_diag[i].cwiseProduct(r[i]);
    d = z;
    double rz = dot(r, z);
    while (it < opts.cg_max_iterations) {
      a_times(d, q);
      const double dq = dot(d, q);
      if (!(dq > 0.0)) {
        // Not positive definite along d: keep the progress made; never re-apply a stale
        // warm start.
        if (it == 0) std::fill(dv.begin(), dv.end(), Vec3::Zero());
        break;
      }
      const double alpha = rz / dq;
      for (std::size_t i = 0; i < n; ++i) {
        dv[i] += alpha * d[i];
        r[i] -= alpha * q[i];
      }
      ++it;
      rnorm = std::sqrt(dot(r, r));
      if (rnorm <= opts.cg_tolerance * bnorm) break;
      for (std::size_t i = 0; i < n; ++i) z[i] = inv_diag[i].cwiseProduct(r[i]);
      const double rz_new = dot(r, z);
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
    if (!free[i]) continue;
    v[i] += dv[i];
    x[i] += dt_s * v[i];
  }
}

}  // namespace integrators
}  // namespace ido::sim
