// SPDX-License-Identifier: Apache-2.0
#include "ido/view/deform_session.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <deque>
#include <fstream>
#include <optional>
#include <sstream>
#include <string_view>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "ido/core/error.h"
#include "ido/sim/diagnostics.h"
#include "ido/sim/fem_common.h"
#include "ido/sim/mass_spring.h"
#include "ido/sim/mls.h"
#include "ido/sim/runner.h"
#include "ido/sim/shape_matching.h"

namespace ido::view {
namespace {

double equivalent_strain(const Mat3& e) {
  const Mat3 dev = e - e.trace() / 3.0 * Mat3::Identity();
  return std::sqrt(2.0 / 3.0 * dev.cwiseProduct(dev).sum());
}

/// The numbers of a scene file that can be changed between steps (SceneParameter).
std::vector<SceneParameter> scene_parameters(const nlohmann::json& doc) {
  std::vector<SceneParameter> out;
  const auto& bodies = doc.at("bodies");
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const auto& b = bodies[i];
    const std::string name = b.contains("name") && b["name"].is_string() && !b["name"].get<std::string>().empty()
                                 ? b["name"].get<std::string>()
                                 : fmt::format("body {}", i);
    const std::string base = fmt::format("/bodies/{}", i);
    if (b.contains("material") && b["material"].is_object()) {
      const auto& m = b["material"];
      for (const auto& [key, label] : {std::pair{"youngs_modulus_pa", "Young's modulus (Pa)"},
                                       {"poisson_ratio", "Poisson ratio"},
                                       {"density_kg_m3", "density (kg/m3)"}})
        if (m.contains(key) && m[key].is_number())
          out.push_back({base + "/material/" + key, name + ": " + label, m[key].get<double>()});
    }
    for (const char* model : {"mass_spring", "shape_matching", "mls"})
      if (b.contains(model) && b[model].is_object())
        for (const auto& [key, value] : b[model].items())
          if (value.is_number())
            out.push_back({base + "/" + model + "/" + key, name + ": " + model + " " + key, value.get<double>()});
  }
  for (const auto& [key, label] : {std::pair{"rayleigh_mass_per_s", "damping alpha (1/s)"},
                                   {"rayleigh_stiffness_s", "damping beta (s)"}}) {
    double v = 0.0;
    if (doc.contains("damping") && doc["damping"].is_object() && doc["damping"].contains(key) &&
        doc["damping"][key].is_number())
      v = doc["damping"][key].get<double>();
    out.push_back({std::string("/damping/") + key, label, v});
  }
  return out;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  if (!in) throw IoError(path.string(), "cannot read the scene file");
  return text.str();
}

/// What a parameter changes in a running world: a number one of its objects can take in place
/// (a force model's setter, the Rayleigh damping), or something built from it (the particles'
/// masses from the density, shape-matching clusters, MLS neighbourhoods), which only a world
/// built anew can change.
enum class ParameterRole {
  YoungsModulus, PoissonRatio, SpringStiffness, SpringDamping, MatchingStiffness, MatchingBeta,
  MlsVolumeStiffness, DampingAlpha, DampingBeta, Rebuild
};

struct ParameterTarget {
  ParameterRole role = ParameterRole::Rebuild;
  std::size_t body = 0;
};

/// The target of a SceneParameter::pointer ("/bodies/0/material/youngs_modulus_pa",
/// "/bodies/1/mass_spring/stiffness_n_per_mm", "/damping/rayleigh_mass_per_s", ...).
ParameterTarget parameter_target(const std::string& pointer) {
  static const std::pair<const char*, ParameterRole> kRoles[] = {
      {"/material/youngs_modulus_pa", ParameterRole::YoungsModulus},
      {"/material/poisson_ratio", ParameterRole::PoissonRatio},
      {"/mass_spring/stiffness_n_per_mm", ParameterRole::SpringStiffness},
      {"/mass_spring/damping_n_s_per_mm", ParameterRole::SpringDamping},
      {"/shape_matching/stiffness_per_s2", ParameterRole::MatchingStiffness},
      {"/shape_matching/beta", ParameterRole::MatchingBeta},
      {"/mls/volume_stiffness_pa", ParameterRole::MlsVolumeStiffness}};
  if (pointer == "/damping/rayleigh_mass_per_s") return {ParameterRole::DampingAlpha, 0};
  if (pointer == "/damping/rayleigh_stiffness_s") return {ParameterRole::DampingBeta, 0};
  constexpr std::string_view kBodies = "/bodies/";
  if (!pointer.starts_with(kBodies)) return {};
  std::size_t body = 0;
  const std::size_t slash = pointer.find('/', kBodies.size());
  if (slash == std::string::npos) return {};
  const auto [end, ec] = std::from_chars(pointer.data() + kBodies.size(), pointer.data() + slash, body);
  if (ec != std::errc() || end != pointer.data() + slash) return {};
  const std::string_view rest = std::string_view(pointer).substr(slash);
  for (const auto& [suffix, role] : kRoles)
    if (rest == suffix) return {role, body};
  return {};
}

/// Gives @p world the values of the changed parameters @p changed through its objects' setters
/// (force models, damping), or returns false having changed nothing when one of them needs a
/// world built anew. @p bodies are the scene's (their material is the stress output's).
bool set_in_place(sim::World& world, std::vector<io::SceneBody>& bodies, const std::vector<SceneParameter>& parameters,
                  const std::vector<std::size_t>& changed, const std::vector<double>& values) {
  std::vector<ParameterTarget> targets;
  for (std::size_t i : changed) {
    const ParameterTarget t = parameter_target(parameters[i].pointer);
    if (t.role == ParameterRole::Rebuild) return false;
    if (t.role != ParameterRole::DampingAlpha && t.role != ParameterRole::DampingBeta) {
      if (t.body >= bodies.size() || bodies[t.body].model_index >= world.models().size()) return false;
      sim::ForceModel* model = world.models()[bodies[t.body].model_index].get();
      const bool fits = [&] {
        switch (t.role) {
          case ParameterRole::SpringStiffness:
          case ParameterRole::SpringDamping: return dynamic_cast<sim::MassSpring*>(model) != nullptr;
          case ParameterRole::MatchingStiffness:
          case ParameterRole::MatchingBeta: return dynamic_cast<sim::ShapeMatching*>(model) != nullptr;
          case ParameterRole::MlsVolumeStiffness: return dynamic_cast<sim::MlsElasticity*>(model) != nullptr;
          default: return true;  // a material: the model's own, or the stress output's only
        }
      }();
      if (!fits) return false;
    }
    targets.push_back(t);
  }
  // The values were checked by the scene reader, whose ranges are those of the setters or
  // narrower, so no setter below refuses one.
  for (std::size_t k = 0; k < changed.size(); ++k) {
    const double v = values[changed[k]];
    const ParameterTarget& t = targets[k];
    if (t.role == ParameterRole::DampingAlpha) {
      world.external().damping.mass_per_s = v;
      continue;
    }
    if (t.role == ParameterRole::DampingBeta) {
      world.external().damping.stiffness_s = v;
      continue;
    }
    io::SceneBody& body = bodies[t.body];
    sim::ForceModel* model = world.models()[body.model_index].get();
    switch (t.role) {
      case ParameterRole::YoungsModulus:
      case ParameterRole::PoissonRatio:
        (t.role == ParameterRole::YoungsModulus ? body.material.youngs_modulus_pa : body.material.poisson_ratio) = v;
        if (auto* fem = dynamic_cast<sim::TetFemModel*>(model)) fem->set_material(body.material);
        if (auto* mls = dynamic_cast<sim::MlsElasticity*>(model)) mls->set_material(body.material);
        break;
      case ParameterRole::SpringStiffness: static_cast<sim::MassSpring*>(model)->set_stiffness(v); break;
      case ParameterRole::SpringDamping: static_cast<sim::MassSpring*>(model)->set_damping(v); break;
      case ParameterRole::MatchingStiffness: static_cast<sim::ShapeMatching*>(model)->set_stiffness(v); break;
      case ParameterRole::MatchingBeta: static_cast<sim::ShapeMatching*>(model)->set_beta(v); break;
      case ParameterRole::MlsVolumeStiffness: static_cast<sim::MlsElasticity*>(model)->set_volume_stiffness(v); break;
      default: break;
    }
  }
  return true;
}

}  // namespace

DeformSession::DeformSession(io::Scene scene) : m_scene(std::move(scene)) {
  if (m_scene.bodies.empty()) throw InvalidInput("the scene has no bodies to deform");
  m_bodies = m_scene.bodies;
  m_integrator_names = m_scene.world.integrators().names();
  m_dt_s = m_scene.dt_s;
  m_thread = std::thread([this] { work(); });
}

DeformSession::DeformSession(const std::filesystem::path& scene_file) : m_scene(io::load_scene(scene_file)) {
  if (m_scene.bodies.empty()) throw InvalidInput("the scene has no bodies to deform");
  m_scene_text = read_text(scene_file);
  m_base_dir = scene_file.parent_path();
  m_parameters = scene_parameters(nlohmann::json::parse(m_scene_text));  // load_scene read it: valid JSON
  m_bodies = m_scene.bodies;
  m_integrator_names = m_scene.world.integrators().names();
  m_dt_s = m_scene.dt_s;
  m_thread = std::thread([this] { work(); });
}

void DeformSession::set_parameters(const std::vector<double>& values) {
  if (values.size() != m_parameters.size())
    throw InvalidInput(fmt::format("{} parameter values given for the scene's {}", values.size(), m_parameters.size()));
  m_parameter_requests.write(std::make_shared<const std::vector<double>>(values));
}

bool DeformSession::apply_parameters(const std::vector<double>& values, std::vector<double>& in_use,
                                     std::vector<ParameterChange>& changes, std::string& error) {
  error.clear();
  if (values == in_use) return false;
  // The scene file with the new values, read again by the library, which checks them: the one
  // rule for what a scene takes, with its messages naming the JSON pointer.
  nlohmann::json doc = nlohmann::json::parse(m_scene_text);
  for (std::size_t i = 0; i < values.size(); ++i)
    if (values[i] != m_parameters[i].value) doc[nlohmann::json::json_pointer(m_parameters[i].pointer)] = values[i];
  io::Scene fresh;
  try {
    fresh = io::parse_scene(doc.dump(), m_scene.source, m_base_dir);
  } catch (const std::exception& e) {
    error = e.what();
    return false;
  }
  sim::World& old = m_scene.world;
  if (fresh.world.particles().size() != old.particles().size()) {
    error = "the changed scene has other particles";
    return false;
  }
  std::vector<std::size_t> changed;
  for (std::size_t i = 0; i < values.size(); ++i)
    if (values[i] != in_use[i]) changed.push_back(i);
  const std::int64_t step = m_step_base + old.step_count();
  // Numbers the running objects take through their setters change in place: positions,
  // velocities, the integrator's state and the models' caches go on. Otherwise the new world
  // goes on from the old one's particles and integrator.
  if (!set_in_place(old, m_scene.bodies, m_parameters, changed, values)) {
    fresh.world.particles().positions() = old.particles().positions();
    fresh.world.particles().velocities() = old.particles().velocities();
    fresh.world.set_integrator(old.integrator());
    m_step_base = step;
    m_time_base_s += old.time_s();
    m_scene = std::move(fresh);
  }
  for (std::size_t i : changed) changes.push_back({step, m_parameters[i].pointer, values[i]});
  in_use = values;
  return true;
}

DeformSession::~DeformSession() {
  m_stop = true;
  if (m_thread.joinable()) m_thread.join();
}

void DeformSession::set_integrator(const std::string& name) {
  const auto it = std::find(m_integrator_names.begin(), m_integrator_names.end(), name);
  if (it == m_integrator_names.end()) throw InvalidInput("unknown integrator '" + name + "'");
  m_integrator_request.store(int(it - m_integrator_names.begin()));
}

std::vector<std::int32_t> DeformSession::grab_group(std::int32_t particle) const {
  std::vector<std::int32_t> group = {particle};
  for (const io::SceneBody& b : m_bodies) {
    const std::int32_t local = particle - b.first_particle;
    if (local < 0 || std::size_t(local) >= b.rest_mesh.vertices.size()) continue;
    for (const Tet& t : b.rest_mesh.tets)
      if (std::find(t.begin(), t.end(), local) != t.end())
        for (std::int32_t v : t) group.push_back(v + b.first_particle);
  }
  std::sort(group.begin(), group.end());
  group.erase(std::unique(group.begin(), group.end()), group.end());
  return group;
}

std::shared_ptr<const DeformState> DeformSession::latest() {
  if (m_states.has_new()) m_latest = m_states.read();
  return m_latest;
}

void DeformSession::work() {
  sim::World& world = m_scene.world;  // the same object when a parameter change replaces the world's content
  std::vector<sim::PointLoad> base_loads = world.external().point_loads;
  std::deque<EnergySample> history;
  std::string error;
  std::int32_t grabbed = -1;
  std::vector<std::int32_t> group;
  double grab_k = 0.0;
  std::vector<double> in_use;
  for (const SceneParameter& p : m_parameters) in_use.push_back(p.value);
  std::vector<ParameterChange> changes;
  std::string parameter_error;
  auto publish = [&] {
    auto s = std::make_shared<DeformState>();
    s->steps = m_step_base + world.step_count();
    s->time_s = m_time_base_s + world.time_s();
    s->integrator = world.integrator();
    s->positions_mm = world.particles().positions();
    s->linear_momentum = sim::momentum(world.particles()).linear_kg_mm_s;
    for (const io::SceneBody& b : m_bodies) {
      std::vector<double> vm, strain;
      if (b.stress_model_index < world.models().size())
        if (const auto f = world.models()[b.stress_model_index]->element_fields(world.particles())) {
          vm = f->von_mises_pa;
          for (const Mat3& e : f->green_strain) strain.push_back(equivalent_strain(e));
        }
      s->von_mises_pa.push_back(std::move(vm));
      s->equivalent_strain.push_back(std::move(strain));
    }
    s->history.assign(history.begin(), history.end());
    s->error = error;
    s->grab_stiffness_n_per_mm = grab_k;
    s->parameters = in_use;
    s->changes = changes;
    s->parameter_error = parameter_error;
    m_states.write(std::shared_ptr<const DeformState>(std::move(s)));
  };
  // The project's divergence rule (sim::DivergenceWatch, as sim::run applies it) with the
  // scene's energy floor (io::run_options). It starts again from the present state whenever the
  // world's loads or models change between steps: a parameter change, and every step the pull
  // acts or has just been let go of (the pull is a load that changes each step).
  std::optional<sim::DivergenceWatch> watch;
  std::vector<sim::PointLoad> watched_loads;
  auto watch_from_here = [&] {
    watch.emplace(world, m_dt_s, io::run_options(m_scene).energy_floor_mj);
    watched_loads = world.external().point_loads;
  };
  auto same_loads = [](const std::vector<sim::PointLoad>& a, const std::vector<sim::PointLoad>& b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const sim::PointLoad& x, const sim::PointLoad& y) {
      return x.particle == y.particle && x.force_n == y.force_n;
    });
  };
  auto sample = [&](double step_ms, const sim::EnergyReport& e) {
    history.push_back({m_time_base_s + world.time_s(), e.kinetic_mj, e.elastic_total_mj(), e.total_mj(), step_ms});
    if (history.size() > DeformState::kHistory) history.pop_front();
  };
  sample(0.0, sim::energies(world));
  watch_from_here();
  publish();
  bool unpublished = false;  // steps taken since the last state handed over
  while (!m_stop) {
    const bool requested = m_step_requests.load() > 0;
    // Parameter changes: between two steps, and at once while paused. Read after the step
    // requests, so values set before a step was asked for are in use for that step.
    if (m_parameter_requests.has_new()) {
      const std::shared_ptr<const std::vector<double>> wanted = m_parameter_requests.read();
      if (wanted && !m_scene_text.empty()) {
        if (apply_parameters(*wanted, in_use, changes, parameter_error)) {
          base_loads = world.external().point_loads;
          watch_from_here();
        }
        publish();
        unpublished = false;
      }
    }
    if (!error.empty() || (!m_running && !requested)) {
      if (unpublished) publish();  // the state the run stopped at
      unpublished = false;
      if (requested) m_step_requests.store(0);
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      continue;
    }
    if (const int i = m_integrator_request.exchange(-1); i >= 0) world.set_integrator(m_integrator_names[std::size_t(i)]);
    // The grab spring is a point load recomputed from the particle's position before each step.
    world.external().point_loads = base_loads;
    const GrabSpring& g = m_grab.read();
    grab_k = 0.0;
    if (g.active && g.particle >= 0 && std::size_t(g.particle) < world.particles().size()) {
      if (g.particle != grabbed) {
        group = grab_group(g.particle);
        grabbed = g.particle;
      }
      const auto& x = world.particles().positions();
      const auto& m = world.particles().masses();
      double mass = 0.0;
      Vec3 centre = Vec3::Zero();
      for (std::int32_t i : group) {
        mass += m[std::size_t(i)];
        centre += m[std::size_t(i)] * x[std::size_t(i)];
      }
      if (mass > 0) {
        centre /= mass;
        grab_k = std::min(g.stiffness_n_per_mm, 2.0 * mass / (m_dt_s * m_dt_s * 1e3));
        for (std::int32_t i : group)
          world.external().point_loads.push_back({i, m[std::size_t(i)] / mass * grab_k * (g.target_mm - centre)});
      }
    }
    if (!same_loads(world.external().point_loads, watched_loads)) watch_from_here();
    const auto t0 = std::chrono::steady_clock::now();
    try {
      world.step(m_dt_s);
    } catch (const std::exception& e) {
      error = e.what();
    }
    const double step_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const sim::EnergyReport energy = sim::energies(world);
    if (error.empty()) {
      std::optional<std::string> cause = watch->check_finite(world);
      if (!cause) cause = watch->check_energy(world, energy);
      if (cause)
        error = watch->message(m_step_base + world.step_count(), std::nullopt, m_time_base_s + world.time_s(), *cause);
    }
    sample(step_ms, energy);
    if (requested) m_step_requests.fetch_sub(1);
    unpublished = true;
    if (!m_states.has_new() || requested || !error.empty()) {
      publish();
      unpublished = false;
    }
  }
}

}  // namespace ido::view
