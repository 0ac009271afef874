// SPDX-License-Identifier: Apache-2.0
// The simulation library (the paper's IdoLib) seen from Python: ido.World with tetrahedral
// bodies, FEM and spring models, external forces, run-time switchable integrators (Python
// functions among them) and one call per step; energies and momentum; scene files.
// Particle arrays cross as copies (n, 3): the world may grow, so a view could dangle.
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "arrays.h"
#include "bindings.h"
#include "ido/core/error.h"
#include "ido/io/scene.h"
#include "ido/sim/diagnostics.h"
#include "ido/sim/fem_corotational.h"
#include "ido/sim/fem_linear.h"
#include "ido/sim/fem_neo_hookean.h"
#include "ido/sim/generators.h"
#include "ido/sim/mass_spring.h"
#include "ido/sim/mls.h"
#include "ido/sim/units.h"
#include "ido/sim/world.h"

namespace py = pybind11;

namespace ido::python {
namespace {

using sim::World;

/// Replaces @p dst by the rows of @p a, which must be (n, 3) with n = dst.size().
void assign_points(std::vector<Vec3>& dst, const Points& a, const char* what) {
  if (a.ndim() != 2 || a.shape(1) != 3 || std::size_t(a.shape(0)) != dst.size())
    throw InvalidInput(std::string(what) + ": expected an array of shape (" + std::to_string(dst.size()) + ", 3)");
  dst = points_from_array(a, what);
}

/// The tetrahedra of @p mesh as particle indices (vertex v is particle first_particle + v).
std::vector<Tet> body_tets(const World& w, const geometry::TetMesh& mesh, std::int64_t first_particle) {
  if (first_particle < 0 || std::size_t(first_particle) + mesh.vertices.size() > w.particles().size())
    throw InvalidInput("first_particle " + std::to_string(first_particle) + ": the body's " +
                       std::to_string(mesh.vertices.size()) + " vertices do not fit the world's " +
                       std::to_string(w.particles().size()) + " particles (add_tet_body first)");
  std::vector<Tet> tets = mesh.tets;
  for (Tet& t : tets)
    for (auto& v : t) v += std::int32_t(first_particle);
  return tets;
}

}  // namespace

void bind_sim(py::module_& m) {
  m.attr("STANDARD_GRAVITY_MM_S2") = sim::kStandardGravityMmPerS2;

  py::class_<World>(m, "World",
                    "Particles and the relations between them (force models), external forces, and a time "
                    "integrator chosen by name that can change between any two steps. Units: mm, kg, s, N; "
                    "energies in mJ. One call of step() is one step: the loop is the caller's.")
      .def(py::init<>())
      .def("__repr__",
           [](const World& w) {
             return fmt::format("<ido.World {} particles, {} force models, integrator {}, step {}>", w.particles().size(),
                                w.models().size(), w.integrator(), w.step_count());
           })
      .def(
          "add_tet_body",
          [](World& w, const geometry::TetMesh& mesh, double density_kg_m3) {
            return w.add_tet_body(mesh, density_kg_m3);
          },
          py::arg("mesh"), py::arg("density_kg_m3"),
          "Adds one particle per vertex with lumped masses from the density; returns the first particle's index.")
      .def(
          "add_fem",
          [](World& w, const geometry::TetMesh& mesh, const std::string& kind, double youngs_modulus_pa,
             double poisson_ratio, std::int64_t first_particle) {
            std::vector<Tet> tets = body_tets(w, mesh, first_particle);
            const sim::ElasticMaterial mat{.youngs_modulus_pa = youngs_modulus_pa, .poisson_ratio = poisson_ratio};
            const auto& x = w.particles().positions();
            if (kind == "corotational")
              w.emplace_model<sim::CorotationalFem>(std::move(tets), x, mat);
            else if (kind == "linear")
              w.emplace_model<sim::LinearFem>(std::move(tets), x, mat);
            else if (kind == "neo_hookean")
              w.emplace_model<sim::NeoHookeanFem>(std::move(tets), x, mat);
            else
              throw InvalidInput("add_fem: unknown kind '" + kind + "' (corotational, linear, neo_hookean)");
            return w.models().size() - 1;
          },
          py::arg("mesh"), py::kw_only(), py::arg("kind") = "corotational", py::arg("youngs_modulus_pa") = 1e5,
          py::arg("poisson_ratio") = 0.3, py::arg("first_particle") = 0,
          "Finite elements on a body added with add_tet_body (its rest shape: the particles' present positions). "
          "kind: corotational, linear or neo_hookean. Returns the model's index.")
      .def(
          "set_material",
          [](World& w, std::size_t model, std::optional<double> youngs_modulus_pa, std::optional<double> poisson_ratio) {
            if (model >= w.models().size())
              throw InvalidInput("set_material: model " + std::to_string(model) + " does not exist (" +
                                 std::to_string(w.models().size()) + " models)");
            auto& target = *w.models()[model];
            if (auto* fem = dynamic_cast<sim::TetFemModel*>(&target)) {
              fem->set_material({.youngs_modulus_pa = youngs_modulus_pa.value_or(fem->material().youngs_modulus_pa),
                                 .poisson_ratio = poisson_ratio.value_or(fem->material().poisson_ratio)});
            } else if (auto* mls = dynamic_cast<sim::MlsElasticity*>(&target)) {
              const auto& old = mls->options().material;
              mls->set_material({.youngs_modulus_pa = youngs_modulus_pa.value_or(old.youngs_modulus_pa),
                                 .poisson_ratio = poisson_ratio.value_or(old.poisson_ratio)});
            } else {
              throw InvalidInput(
                  fmt::format("set_material: model {} ({}) has no elastic material", model, target.kind()));
            }
          },
          py::arg("model"), py::kw_only(), py::arg("youngs_modulus_pa") = py::none(),
          py::arg("poisson_ratio") = py::none(),
          "Changes an FEM (or MLS) model's Young's modulus (Pa) and/or Poisson ratio between steps; "
          "model is the index add_fem returned. Raises ValueError naming a value out of range.")
      .def(
          "set_springs",
          [](World& w, std::size_t model, std::optional<double> stiffness_n_per_mm,
             std::optional<double> damping_n_s_per_mm) {
            if (model >= w.models().size())
              throw InvalidInput("set_springs: model " + std::to_string(model) + " does not exist (" +
                                 std::to_string(w.models().size()) + " models)");
            auto* springs = dynamic_cast<sim::MassSpring*>(w.models()[model].get());
            if (!springs)
              throw InvalidInput(fmt::format("set_springs: model {} ({}) is not a mass-spring model", model,
                                             w.models()[model]->kind()));
            if (stiffness_n_per_mm) springs->set_stiffness(*stiffness_n_per_mm);
            if (damping_n_s_per_mm) springs->set_damping(*damping_n_s_per_mm);
          },
          py::arg("model"), py::kw_only(), py::arg("stiffness_n_per_mm") = py::none(),
          py::arg("damping_n_s_per_mm") = py::none(),
          "Changes every spring's stiffness (N/mm) and/or damping (N·s/mm) of a mass-spring model between steps.")
      .def(
          "add_springs",
          [](World& w, const geometry::TetMesh& mesh, double stiffness_n_per_mm, double damping_n_s_per_mm,
             std::int64_t first_particle) {
            (void)body_tets(w, mesh, first_particle);  // range check
            w.add_model(std::make_unique<sim::MassSpring>(sim::MassSpring::from_tet_edges(
                mesh, std::int32_t(first_particle), stiffness_n_per_mm, damping_n_s_per_mm)));
            return w.models().size() - 1;
          },
          py::arg("mesh"), py::kw_only(), py::arg("stiffness_n_per_mm"), py::arg("damping_n_s_per_mm") = 0.0,
          py::arg("first_particle") = 0, "Springs along the mesh's edges (mass-spring). Returns the model's index.")
      .def_property_readonly("particle_count", [](const World& w) { return w.particles().size(); })
      .def_property(
          "positions", [](const World& w) { return points_to_array(w.particles().positions()); },
          [](World& w, const Points& a) { assign_points(w.particles().positions(), a, "positions"); },
          "Particle positions (n, 3), mm: a copy; assign an array of the same shape to move them.")
      .def_property(
          "velocities", [](const World& w) { return points_to_array(w.particles().velocities()); },
          [](World& w, const Points& a) { assign_points(w.particles().velocities(), a, "velocities"); },
          "Particle velocities (n, 3), mm/s: a copy; assignable.")
      .def_property_readonly(
          "masses",
          [](const World& w) {
            const auto& ms = w.particles().masses();
            return py::array_t<double>(py::ssize_t(ms.size()), ms.data());
          },
          "Particle masses (n,), kg (a copy).")
      .def_property_readonly(
          "fixed",
          [](const World& w) {
            py::array_t<bool> out(py::ssize_t(w.particles().size()));
            auto o = out.mutable_unchecked<1>();
            for (std::size_t i = 0; i < w.particles().size(); ++i) o(py::ssize_t(i)) = w.particles().fixed(i);
            return out;
          },
          "Which particles are fixed (n,) (a copy).")
      .def(
          "set_fixed",
          [](World& w, const std::vector<std::int64_t>& indices, bool fixed) {
            for (std::int64_t i : indices)
              if (i < 0 || std::size_t(i) >= w.particles().size())
                throw InvalidInput("set_fixed: particle " + std::to_string(i) + " does not exist (" +
                                   std::to_string(w.particles().size()) + " particles)");
            for (std::int64_t i : indices) w.particles().set_fixed(std::size_t(i), fixed);
          },
          py::arg("indices"), py::arg("fixed") = true, "Fixes (or frees) the given particles.")
      .def_property(
          "gravity_mm_s2", [](const World& w) { return w.external().gravity_mm_s2; },
          [](World& w, const Vec3& g) { w.external().gravity_mm_s2 = g; },
          "Gravity (mm/s²), e.g. (0, 0, -ido.STANDARD_GRAVITY_MM_S2).")
      .def(
          "set_damping",
          [](World& w, double mass_per_s, double stiffness_s) {
            if (!(mass_per_s >= 0) || !(stiffness_s >= 0)) throw InvalidInput("set_damping: coefficients must be >= 0");
            w.external().damping = {.mass_per_s = mass_per_s, .stiffness_s = stiffness_s};
          },
          py::arg("mass_per_s") = 0.0, py::arg("stiffness_s") = 0.0, "Rayleigh damping: alpha (1/s), beta (s).")
      .def(
          "add_point_load",
          [](World& w, std::int64_t particle, const Vec3& force_n) {
            if (particle < 0 || std::size_t(particle) >= w.particles().size())
              throw InvalidInput("add_point_load: particle " + std::to_string(particle) + " does not exist");
            w.external().point_loads.push_back({.particle = std::int32_t(particle), .force_n = force_n});
          },
          py::arg("particle"), py::arg("force_n"), "A constant force (N) on one particle.")
      .def(
          "add_plane",
          [](World& w, const Vec3& point_mm, const Vec3& normal) {
            if (!(normal.norm() > 0)) throw InvalidInput("add_plane: the normal must not be zero");
            w.external().planes.push_back({.point_mm = point_mm, .normal = normal});
          },
          py::arg("point_mm"), py::arg("normal"), "A rigid frictionless floor {x: (x - point) . normal >= 0}.")
      .def_property(
          "integrator", [](const World& w) { return w.integrator(); },
          [](World& w, const std::string& name) { w.set_integrator(name); },
          "The scheme step() uses, by name; may change between any two steps.")
      .def(
          "integrators", [](World& w) { return w.integrators().names(); },
          "The registered schemes' names (built-in: explicit_euler, symplectic_euler, velocity_verlet, rk4, "
          "implicit_euler, ...).")
      .def(
          "add_integrator",
          [](World& w, const std::string& name, py::function fn) {
            // Called from step(), which runs without the GIL: take it for the Python call.
            w.integrators().add(name, [fn](World& world, double dt_s) {
              py::gil_scoped_acquire locked;
              fn(py::cast(&world, py::return_value_policy::reference), dt_s);
            });
          },
          py::arg("name"), py::arg("fn"),
          "Registers a scheme written in Python: fn(world, dt_s) advances the world by one step (read "
          "accelerations(), assign velocities and positions). fn may be an object with state (a class with "
          "__call__, e.g. a Newmark scheme keeping its acceleration): the world calls the same object every step. "
          "Select it with world.integrator = name.")
      .def(
          "accelerations",
          [](World& w) {
            w.compute_forces();
            return points_to_array(w.accelerations());
          },
          "Computes the forces at the present state and returns the accelerations (n, 3), mm/s².")
      .def(
          "step",
          [](World& w, double dt_s, int steps) {
            if (steps < 1) throw InvalidInput("step: steps must be at least 1");
            py::gil_scoped_release unlocked;
            for (int s = 0; s < steps; ++s) w.step(dt_s);
          },
          py::arg("dt_s"), py::arg("steps") = 1, "Advances by `steps` steps of dt_s seconds with the chosen scheme.")
      .def_property_readonly("time_s", &World::time_s)
      .def_property_readonly("step_count", &World::step_count)
      .def_property_readonly(
          "last_step",
          [](const World& w) {
            py::dict d;
            d["cg_iterations"] = w.last_step().cg_iterations;
            d["cg_relative_residual"] = w.last_step().cg_relative_residual;
            d["force_evaluations"] = w.last_step().force_evaluations;
            return d;
          },
          "What the last step cost: CG iterations and residual (implicit schemes), force evaluations.")
      .def(
          "energies", [](const World& w) { return to_python(io::to_json(sim::energies(w))); },
          "Kinetic, gravitational and per-model elastic energy (mJ) at the present state.")
      .def(
          "momentum",
          [](const World& w, const Vec3& origin_mm) {
            const auto p = sim::momentum(w.particles(), origin_mm);
            return py::make_tuple(p.linear_kg_mm_s, p.angular_kg_mm2_s);
          },
          py::arg("origin_mm") = Vec3(Vec3::Zero()), "(linear kg·mm/s, angular kg·mm²/s about origin_mm).")
      .def(
          "solve_static",
          [](World& w, int max_newton_iterations, double force_tolerance_n) {
            sim::StaticSolveResult r;
            {
              py::gil_scoped_release unlocked;
              r = sim::solve_static(w, {.max_newton_iterations = max_newton_iterations,
                                        .force_tolerance_n = force_tolerance_n});
            }
            py::dict d;
            d["newton_iterations"] = r.newton_iterations;
            d["max_residual_force_n"] = r.max_residual_force_n;
            d["converged"] = r.converged;
            return d;
          },
          py::arg("max_newton_iterations") = 20, py::arg("force_tolerance_n") = 1e-9,
          "Newton's method to static equilibrium under the present loads.");

  m.def(
      "make_beam",
      [](const Vec3& size_mm, const std::array<int, 3>& cells, const Vec3& origin_mm) {
        return sim::make_beam(size_mm, Vec3i(cells[0], cells[1], cells[2]), origin_mm);
      },
      py::arg("size_mm"), py::arg("cells"), py::arg("origin_mm") = Vec3(Vec3::Zero()),
      "A box [origin, origin + size] of cells[0] x cells[1] x cells[2] hexahedra, six tetrahedra each.");
  m.def(
      "make_sphere",
      [](double radius_mm, int cells_per_radius, const Vec3& centre_mm) {
        return sim::make_sphere(radius_mm, cells_per_radius, centre_mm);
      },
      py::arg("radius_mm"), py::arg("cells_per_radius"), py::arg("centre_mm") = Vec3(Vec3::Zero()),
      "A voxel-style ball of tetrahedra.");

  py::class_<io::Scene>(m, "Scene", "A scene file loaded: its world, time step, step count and bodies.")
      .def_readonly("world", &io::Scene::world, "The world, ready to step (a reference into the scene).")
      .def("__repr__",
           [](const io::Scene& sc) {
             return fmt::format("<ido.Scene {}: {} bodies, {} steps of {:g} s>", sc.source, sc.bodies.size(), sc.steps,
                                sc.dt_s);
           })
      .def_readonly("dt_s", &io::Scene::dt_s)
      .def_readonly("steps", &io::Scene::steps)
      .def_property_readonly("bodies", [](const io::Scene& s) {
        py::list out;
        for (const auto& b : s.bodies) {
          py::dict d;
          d["name"] = b.name;
          d["first_particle"] = b.first_particle;
          d["rest_mesh"] = b.rest_mesh;
          d["model_index"] = b.model_index;
          out.append(d);
        }
        return out;
      });
  m.def(
      "load_scene", [](const std::filesystem::path& path) { return io::load_scene(path); }, py::arg("path"),
      "Reads a scene file (JSON, docs/scene.md) into a world ready to step.");
}

}  // namespace ido::python
