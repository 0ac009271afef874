# SPDX-License-Identifier: Apache-2.0
"""ido.World: analytic motion, conservation, run-time and Python integrators, statics, scenes."""
import json

import numpy as np
import pytest

import ido

G = np.array([0.0, 0.0, -ido.STANDARD_GRAVITY_MM_S2])


def beam_world(kind="corotational", clamp=True, gravity=True):
    beam = ido.make_beam((40.0, 8.0, 8.0), (8, 2, 2))
    w = ido.World()
    first = w.add_tet_body(beam, density_kg_m3=1000.0)
    w.add_fem(beam, kind=kind, youngs_modulus_pa=2e5, poisson_ratio=0.3, first_particle=first)
    if clamp:
        w.set_fixed(np.flatnonzero(beam.vertices[:, 0] < 1e-9).tolist())
    if gravity:
        w.gravity_mm_s2 = G
    return beam, w


def test_free_fall_follows_the_symplectic_euler_closed_form():
    w = ido.World()
    w.add_tet_body(ido.make_beam((2.0, 2.0, 2.0), (1, 1, 1)), density_kg_m3=1000.0)
    w.gravity_mm_s2 = G
    x0 = w.positions
    dt, n = 1e-3, 40
    w.integrator = "symplectic_euler"
    w.step(dt, steps=n)
    # v_k = k g dt, x_n = x_0 + g dt² n(n + 1) / 2
    np.testing.assert_allclose(w.positions - x0, np.tile(G * dt * dt * n * (n + 1) / 2, (len(x0), 1)), rtol=1e-12)
    assert w.time_s == pytest.approx(n * dt) and w.step_count == n


def test_python_integrator_equals_the_built_in_one():
    _, built_in = beam_world()
    _, python = beam_world()
    fixed = python.fixed

    def symplectic(world, dt):
        a = world.accelerations()
        a[fixed] = 0.0
        v = world.velocities + dt * a
        world.velocities = v
        world.positions = world.positions + dt * v

    python.add_integrator("python_symplectic", symplectic)
    assert "python_symplectic" in python.integrators()
    python.integrator = "python_symplectic"
    built_in.integrator = "symplectic_euler"
    python.step(2e-4, steps=50)
    built_in.step(2e-4, steps=50)
    np.testing.assert_allclose(python.positions, built_in.positions, rtol=0, atol=1e-12)
    assert np.abs(built_in.positions - beam_world()[1].positions).max() > 1e-4  # it moved


def stretched_free_beam():
    _, w = beam_world(clamp=False, gravity=False)
    rng = np.random.default_rng(7)
    w.positions = w.positions + rng.normal(scale=0.2, size=w.positions.shape)  # elastic energy, no motion
    return w


def test_free_elastic_body_conserves_momentum_when_switching_schemes():
    w = stretched_free_beam()
    p0, l0 = w.momentum()
    e0 = w.energies()["total_mj"]
    assert w.energies()["elastic_mj"] == pytest.approx(e0)
    # Both schemes are symplectic: they keep angular momentum too (rk4 would only keep the linear one).
    for scheme in ["velocity_verlet", "symplectic_euler", "velocity_verlet"]:
        w.integrator = scheme
        w.step(1e-5, steps=100)
    p1, l1 = w.momentum()
    np.testing.assert_allclose(p1, p0, atol=1e-12)
    np.testing.assert_allclose(l1, l0, atol=1e-9)
    assert w.energies()["kinetic_mj"] > 0.1 * e0  # energy moved between the forms


def energy_error(scheme, dt_s, duration_s=6e-3):
    """Largest relative drift of the total energy over the run, sampled ten times."""
    w = stretched_free_beam()
    w.integrator = scheme
    e0 = w.energies()["total_mj"]
    n = int(round(duration_s / dt_s)) // 10
    worst = 0.0
    for _ in range(10):
        w.step(dt_s, steps=n)
        worst = max(worst, abs(w.energies()["total_mj"] - e0) / e0)
    return worst


@pytest.mark.parametrize("scheme,order", [("velocity_verlet", 2), ("symplectic_euler", 1)])
def test_energy_error_shrinks_at_the_scheme_order(scheme, order):
    coarse, fine = energy_error(scheme, 1e-5), energy_error(scheme, 5e-6)
    assert fine < 0.03
    assert 2 ** order * 0.75 < coarse / fine < 2 ** order * 1.33


def test_static_equilibrium_stays_put_under_implicit_steps():
    _, w = beam_world(kind="neo_hookean")
    r = w.solve_static()
    assert r["converged"]
    x = w.positions
    assert x[:, 2].min() < -0.5  # it sagged
    w.integrator = "implicit_euler"
    w.step(0.01, steps=5)
    assert np.abs(w.positions - x).max() < 1e-5
    assert w.last_step["cg_iterations"] >= 0


def test_scene_file_builds_the_same_world_as_the_api(tmp_path):
    scene = {
        "dt_s": 0.002, "steps": 10, "integrator": "implicit_euler", "gravity_mm_s2": G.tolist(),
        "damping": {"rayleigh_mass_per_s": 2.0, "rayleigh_stiffness_s": 0.0},
        "bodies": [{
            "name": "beam", "mesh": {"generator": "beam", "size_mm": [40, 8, 8], "cells": [8, 2, 2]},
            "model": "corotational_fem",
            "material": {"youngs_modulus_pa": 2e5, "poisson_ratio": 0.3, "density_kg_m3": 1000},
            "fixed": [{"box_min_mm": [-1, -1, -1], "box_max_mm": [0.001, 9, 9]}]}]}
    (tmp_path / "s.json").write_text(json.dumps(scene))
    s = ido.load_scene(tmp_path / "s.json")
    assert s.dt_s == 0.002 and s.steps == 10 and s.bodies[0]["name"] == "beam"
    _, w = beam_world()
    w.set_damping(mass_per_s=2.0)
    w.integrator = "implicit_euler"
    assert s.world.integrator == "implicit_euler"
    np.testing.assert_array_equal(s.world.fixed, w.fixed)
    s.world.step(s.dt_s, steps=s.steps)
    w.step(0.002, steps=10)
    np.testing.assert_allclose(s.world.positions, w.positions, rtol=0, atol=1e-12)


def test_bad_input_raises_value_error():
    beam, w = beam_world()
    with pytest.raises(ValueError, match="particle 10000"):
        w.set_fixed([10000])
    with pytest.raises(ValueError, match="unknown kind 'rubber'"):
        w.add_fem(beam, kind="rubber")
    with pytest.raises(ValueError, match=r"shape \(81, 3\)"):
        w.positions = np.zeros((3, 3))
    with pytest.raises(ValueError, match="dt"):
        w.step(-1.0)
    with pytest.raises(ValueError, match="symplectic_euler"):  # the message lists the known schemes
        w.integrator = "leapfrog2"
    with pytest.raises(ValueError, match="do not fit"):
        ido.World().add_fem(beam)
    with pytest.raises(FileNotFoundError, match="nowhere.json"):
        ido.load_scene("/nonexistent/nowhere.json")


def test_reprs_say_what_objects_hold():
    w = ido.World()
    assert repr(w) == "<ido.World 0 particles, 0 force models, integrator symplectic_euler, step 0>"


class CarriedNewmark:
    """Explicit Newmark (beta = 0, gamma = 1/2) that keeps the acceleration of the end of one step
    for the next: state a plain function cannot hold. One force evaluation per step after the first."""

    def __init__(self, fixed):
        self.fixed = fixed
        self.a = None
        self.next_step = -1
        self.evaluations = 0

    def accelerations(self, world):
        self.evaluations += 1
        a = world.accelerations()
        a[self.fixed] = 0.0
        return a

    def __call__(self, world, dt):
        if self.a is None or world.step_count != self.next_step:
            self.a = self.accelerations(world)
        v = world.velocities + 0.5 * dt * self.a
        world.positions = world.positions + dt * v
        self.a = self.accelerations(world)
        world.velocities = v + 0.5 * dt * self.a
        self.next_step = world.step_count + 1


def test_python_integrator_with_state_keeps_it_across_steps_and_switches():
    _, built_in = beam_world()
    _, python = beam_world()
    newmark = CarriedNewmark(python.fixed)
    python.add_integrator("newmark", newmark)
    for w, scheme in ((built_in, "velocity_verlet"), (python, "newmark")):
        w.integrator = scheme
        w.step(2e-4, steps=30)
        w.integrator = "rk4"  # switched away and back: the scheme notices and starts afresh
        w.step(2e-4, steps=5)
        w.integrator = scheme
        w.step(2e-4, steps=30)
    # Velocity Verlet's trajectory, with 1 + 30 + 1 + 30 force evaluations instead of 2 per step.
    np.testing.assert_allclose(python.positions, built_in.positions, rtol=0, atol=1e-10)
    assert newmark.evaluations == 62


def test_set_material_scales_the_static_deflection():
    beam, w = beam_world(kind="linear")
    rest = w.positions
    w.solve_static(force_tolerance_n=1e-12)
    sag = (rest - w.positions)[:, 2].max()
    w.positions = rest
    w.set_material(0, youngs_modulus_pa=4e5)  # twice as stiff: linear elasticity sags half as far
    w.solve_static(force_tolerance_n=1e-12)
    assert (rest - w.positions)[:, 2].max() == pytest.approx(sag / 2, rel=1e-9)
    with pytest.raises(ValueError, match="youngs_modulus_pa"):
        w.set_material(0, youngs_modulus_pa=-1.0)
    with pytest.raises(ValueError, match="poisson_ratio"):
        w.set_material(0, poisson_ratio=0.5)
    springs = w.add_springs(beam, stiffness_n_per_mm=1e-3)
    with pytest.raises(ValueError, match="elastic material"):
        w.set_material(springs, youngs_modulus_pa=1e5)
    with pytest.raises(ValueError, match="stiffness_n_per_mm"):
        w.set_springs(springs, stiffness_n_per_mm=-1.0)
    w.set_springs(springs, stiffness_n_per_mm=2e-3, damping_n_s_per_mm=1e-4)
