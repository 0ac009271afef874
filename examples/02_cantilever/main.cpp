// SPDX-License-Identifier: Apache-2.0
// A corotational-FEM cantilever under a small tip load, solved for static equilibrium and
// compared with Euler–Bernoulli beam theory, δ = F L³ / (3 E I), on refining meshes.
#include <cmath>
#include <cstdio>

#include "ido/sim/fem_corotational.h"
#include "ido/sim/generators.h"
#include "ido/sim/units.h"
#include "ido/sim/world.h"

int main() {
  using namespace ido;
  const double length_mm = 100.0, side_mm = 10.0, youngs_pa = 1e6, load_n = 1e-3;
  const double inertia_mm4 = side_mm * std::pow(side_mm, 3) / 12.0;
  const double analytic_mm = load_n * std::pow(length_mm, 3) / (3.0 * youngs_pa * sim::kPascalToNPerMm2 * inertia_mm4);
  std::printf("Euler-Bernoulli tip deflection: %.5f mm\n", analytic_mm);
  for (int n : {2, 4, 8}) {
    const auto beam = sim::make_beam({length_mm, side_mm, side_mm}, {10 * n, 2, n});
    sim::World world;
    world.add_tet_body(beam, 1000.0);
    world.emplace_model<sim::CorotationalFem>(beam.tets, world.particles().positions(),
                                              sim::ElasticMaterial{youngs_pa, 0.0});
    std::vector<std::int32_t> tip;
    for (std::size_t i = 0; i < beam.vertices.size(); ++i) {
      if (beam.vertices[i].x() < 1e-9) world.particles().set_fixed(i, true);   // clamped end
      if (beam.vertices[i].x() > length_mm - 1e-9) tip.push_back(static_cast<std::int32_t>(i));
    }
    for (auto i : tip) world.external().point_loads.push_back({i, Vec3(0, 0, -load_n / tip.size())});
    const auto result = sim::solve_static(world);
    double deflection = 0.0;
    for (auto i : tip) deflection += beam.vertices[static_cast<std::size_t>(i)].z() - world.particles().positions()[static_cast<std::size_t>(i)].z();
    deflection /= static_cast<double>(tip.size());
    std::printf("%2d cells through the height, %6zu tets: %.5f mm (%+.2f %%), %d Newton steps\n", n,
                beam.tets.size(), deflection, 100.0 * (deflection - analytic_mm) / analytic_mm,
                result.newton_iterations);
  }
  return 0;
}
