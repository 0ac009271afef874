// SPDX-License-Identifier: Apache-2.0
#include "ido/sim/integrator.h"

#include <memory>
#include <string>
#include <utility>

#include "ido/core/error.h"
#include "ido/sim/implicit_euler.h"
#include "ido/sim/world.h"

namespace ido::sim {

// ---- registry ----------------------------------------------------------------------------

namespace {

/// A stateless function as an Integrator. The function is shared with the registry entry
/// (making an instance copies no callable, e.g. no Python object).
class FunctionIntegrator final : public Integrator {
 public:
  FunctionIntegrator(std::string name, std::shared_ptr<const IntegratorFn> fn)
      : m_name(std::move(name)), m_fn(std::move(fn)) {}
  void step(World& world, double dt_s) override { (*m_fn)(world, dt_s); }
  [[nodiscard]] std::string_view name() const override { return m_name; }

 private:
  std::string m_name;
  std::shared_ptr<const IntegratorFn> m_fn;
};

}  // namespace

IntegratorRegistry::IntegratorRegistry() {
  add("explicit_euler", integrators::explicit_euler);
  add("symplectic_euler", integrators::symplectic_euler);
  add("velocity_verlet", integrators::velocity_verlet);
  add("rk4", integrators::rk4);
  add("implicit_euler", IntegratorFactory([] { return std::make_unique<ImplicitEuler>(); }));
}

void IntegratorRegistry::put(const std::string& name, IntegratorFactory factory) {
  m_entries[name] = Entry{std::move(factory), m_next_revision++};
}

void IntegratorRegistry::add(const std::string& name, IntegratorFn fn) {
  if (name.empty()) throw InvalidInput("integrator registry: empty name");
  if (!fn) throw InvalidInput("integrator registry: empty function for '" + name + "'");
  auto shared = std::make_shared<const IntegratorFn>(std::move(fn));
  put(name, [name, shared] { return std::make_unique<FunctionIntegrator>(name, shared); });
}

void IntegratorRegistry::add(const std::string& name, IntegratorFactory factory) {
  if (name.empty()) throw InvalidInput("integrator registry: empty name");
  if (!factory) throw InvalidInput("integrator registry: empty factory for '" + name + "'");
  put(name, std::move(factory));
}

bool IntegratorRegistry::contains(const std::string& name) const { return m_entries.count(name) != 0; }

std::unique_ptr<Integrator> IntegratorRegistry::create(const std::string& name) const {
  const auto it = m_entries.find(name);
  if (it == m_entries.end()) {
    std::string known;
    for (const auto& [k, e] : m_entries) known += (known.empty() ? "" : ", ") + k;
    throw InvalidInput("unknown integrator '" + name + "' (known: " + known + ")");
  }
  auto scheme = it->second.factory();
  if (!scheme) throw InvalidInput("integrator registry: the factory of '" + name + "' made no integrator");
  return scheme;
}

std::uint64_t IntegratorRegistry::revision(const std::string& name) const {
  const auto it = m_entries.find(name);
  return it == m_entries.end() ? 0 : it->second.revision;
}

std::vector<std::string> IntegratorRegistry::names() const {
  std::vector<std::string> out;
  for (const auto& [k, e] : m_entries) out.push_back(k);
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

void implicit_euler(World& world, double dt_s) {
  world.scheme_as<ImplicitEuler>("implicit_euler").step(world, dt_s);
}

}  // namespace integrators
}  // namespace ido::sim
