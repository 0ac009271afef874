// SPDX-License-Identifier: Apache-2.0
// Synthetic CT phantoms; the project's own construction from signed-distance primitives
// (capsule, tapered capsule, torus, capped cylinder; formulas as collected by I. Quilez,
// "distance functions", iquilezles.org).
#include "ido/segment/phantom.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <functional>
#include <string>
#include <tuple>

#include <fmt/format.h>

#include "ido/core/error.h"
#include "ido/core/parallel.h"
#include "ido/image/filters.h"
#include "ido/segment/metrics.h"

namespace ido::segment {
namespace {

using Sdf = std::function<double(const Vec3&)>;

/// √(x² + y²) without std::hypot's overflow care (coordinates are a few hundred mm at most).
inline double hypot2(double x, double y) { return std::sqrt(x * x + y * y); }

// ---- signed distance primitives (mm; negative inside, Lipschitz ≤ 1 + taper slope) ----

double sd_sphere(const Vec3& p, const Vec3& c, double r) { return (p - c).norm() - r; }

/// Capsule / tapered capsule between a (radius ra) and b (radius rb): distance to the
/// segment minus the radius interpolated at the closest segment parameter.
double sd_capsule(const Vec3& p, const Vec3& a, const Vec3& b, double ra, double rb) {
  const Vec3 ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * ab)).norm() - (ra + t * (rb - ra));
}

/// Torus around the z axis through c.
double sd_torus_z(const Vec3& p, const Vec3& c, double big, double small) {
  const Vec3 d = p - c;
  return hypot2(hypot2(d.x(), d.y()) - big, d.z()) - small;
}

/// Cylinder along z through (cx, cy), radius r, z in [zc − h, zc + h].
double sd_cylinder_z(const Vec3& p, const Vec3& c, double r, double h) {
  const double dx = hypot2(p.x() - c.x(), p.y() - c.y()) - r;
  const double dz = std::abs(p.z() - c.z()) - h;
  return std::min(std::max(dx, dz), 0.0) + hypot2(std::max(dx, 0.0), std::max(dz, 0.0));
}

/// Axis-aligned box centred at c with half sizes h (exact distance).
double sd_box(const Vec3& p, const Vec3& c, const Vec3& h) {
  const Vec3 q = (p - c).cwiseAbs() - h;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

/// Axis-aligned ellipsoid centred at c with semi-axes a: not the exact distance but a lower
/// bound of it with the right sign, (|(p − c)/a| − 1) · min(a), since |∇ |(p − c)/a|| ≤
/// 1 / min(a). Enough for the partial-volume test, which needs a lower bound.
double sd_ellipsoid_bound(const Vec3& p, const Vec3& c, const Vec3& a) {
  return ((p - c).cwiseQuotient(a).norm() - 1.0) * a.minCoeff();
}

/// One tissue painted over what lies below it where sdf < 0. With shell_mm > 0 the outer
/// shell_mm of the region gets hu and the rest inner_hu (cortical shell, cancellous core).
struct Layer {
  Sdf sdf;
  double hu = 0.0;
  std::uint8_t label = 0;  ///< truth label of the region (0 = not labelled)
  double shell_mm = 0.0;
  double inner_hu = 0.0;
};

struct Scene {
  Vec3 extent_mm;
  std::vector<Layer> layers;
  std::vector<Vec3> seeds_mm;
  std::vector<int> seed_labels;  ///< label of each seed; empty = all 1
  std::vector<Vec3> drill_path_mm;
  std::string description;
  double object_hu = 0.0;
  double background_hu = 0.0;
  double analytic_volume_mm3 = 0.0;
};

struct Sample {
  double hu;
  std::uint8_t label;
  double boundary_mm;  ///< lower bound of the distance to the nearest tissue boundary
};

/// Tissue at p and a lower bound of its distance to any tissue boundary (Lipschitz bound).
Sample classify(const Scene& s, const PhantomIntensities& hu, const Vec3& p) {
  // Elliptic body cylinder inscribed in the box: fat outside it (only the box corners).
  const double ex = (p.x() - 0.5 * s.extent_mm.x()) / (0.5 * s.extent_mm.x());
  const double ey = (p.y() - 0.5 * s.extent_mm.y()) / (0.5 * s.extent_mm.y());
  const double rho = std::sqrt(ex * ex + ey * ey);
  // |∇ρ| ≤ 1 / smallest semi-axis, so the ellipse is at least |ρ − 1| · semi-axis away.
  Sample out{rho <= 1.0 ? hu.soft_tissue_hu : hu.fat_hu, 0,
             std::abs(rho - 1.0) * 0.5 * std::min(s.extent_mm.x(), s.extent_mm.y())};
  for (const Layer& l : s.layers) {
    const double d = l.sdf(p);
    out.boundary_mm = std::min(out.boundary_mm, std::abs(d));
    if (l.shell_mm > 0.0) out.boundary_mm = std::min(out.boundary_mm, std::abs(d + l.shell_mm));
    if (d >= 0.0) continue;
    out.hu = (l.shell_mm > 0.0 && d < -l.shell_mm) ? l.inner_hu : l.hu;
    out.label = l.label;
  }
  return out;
}

/// The vertebra of the Vertebra phantom moved by @p shift (mm): body r 15 mm, a ring of
/// pedicles and lamina (outer r 13, canal r 8) 12 mm high, spinous and transverse processes.
Sdf vertebra_sdf(const Vec3& shift) {
  const Vec3 body = Vec3(32.1, 50.0, 20.1) + shift, canal = Vec3(32.1, 26.0, 20.1) + shift;
  return [=](const Vec3& p) {
    const double b = sd_cylinder_z(p, body, 15.0, 12.0);
    const double ring = std::max(sd_cylinder_z(p, canal, 13.0, 6.0), -(hypot2(p.x() - canal.x(), p.y() - canal.y()) - 8.0));
    const double spinous = sd_capsule(p, Vec3(32.1, 14.0, 20.1) + shift, Vec3(32.1, 6.0, 16.0) + shift, 3.0, 3.0);
    const double tl = sd_capsule(p, Vec3(21.1, 28.0, 20.1) + shift, Vec3(8.0, 24.0, 20.1) + shift, 3.0, 3.0);
    const double tr = sd_capsule(p, Vec3(43.1, 28.0, 20.1) + shift, Vec3(56.0, 24.0, 20.1) + shift, 3.0, 3.0);
    return std::min({b, ring, spinous, tl, tr});
  };
}

/// Facet-joint processes added to vertebra_sdf(@p shift) for the VertebraStack. On each side
/// of the canal (x = ±10.5 mm from its axis), a superior articular plate (4 × 4 mm in x, y;
/// y 26–30 mm) rises from inside the ring to @p reach_mm above the vertebra's mid-plane, and
/// an inferior plate reaches as far below it, 0.8 mm behind (y 21.2–25.2 mm). Vertebrae
/// stacked 2·(reach_mm − 3) apart thus face each other across a 0.8 mm slit over 6 mm of
/// height on each side: the upper one's inferior plate behind the lower one's superior plate.
Sdf facet_sdf(const Vec3& shift, double reach_mm) {
  const double z0 = 20.1 + shift.z();
  // Mid-height and half-height of plates from 4 mm off the mid-plane (inside the ring, whose
  // half-height is 6 mm) out to reach_mm.
  const double zc = 0.5 * (4.0 + reach_mm), hz = 0.5 * (reach_mm - 4.0);
  const Vec3 half(2.0, 2.0, hz);
  return [=](const Vec3& p) {
    double d = 1e300;
    for (const double side : {-1.0, 1.0}) {
      const double x = 32.1 + shift.x() + side * 10.5;
      d = std::min(d, sd_box(p, Vec3(x, 28.0 + shift.y(), z0 + zc), half));        // superior
      d = std::min(d, sd_box(p, Vec3(x, 23.2 + shift.y(), z0 - zc), half));        // inferior
    }
    return d;
  };
}

/// A pedicle-screw trajectory for the vertebra moved by @p shift: from behind and beside the
/// lamina, through the left pedicle (the ring between canal and body), into the body.
std::vector<Vec3> pedicle_path(const Vec3& shift) {
  return {Vec3(17.0, 12.0, 20.1) + shift, Vec3(19.0, 18.0, 20.1) + shift, Vec3(29.0, 50.0, 20.1) + shift};
}

Scene make_scene(PhantomKind kind, const PhantomOptions& o) {
  const PhantomIntensities& hu = o.intensities;
  Scene s;
  s.background_hu = hu.soft_tissue_hu;
  s.object_hu = hu.vessel_hu;
  auto vessel = [&](Sdf f) { s.layers.push_back({std::move(f), hu.vessel_hu, true, 0.0, 0.0}); };
  switch (kind) {
    case PhantomKind::Sphere: {
      s.extent_mm = {48, 48, 48};
      const Vec3 c(24.2, 23.7, 24.4);
      const double r = 15.0;
      vessel([=](const Vec3& p) { return sd_sphere(p, c, r); });
      s.seeds_mm = {c};
      s.analytic_volume_mm3 = 4.0 / 3.0 * kPi * r * r * r;
      s.description = "sphere of radius 15 mm";
      break;
    }
    case PhantomKind::Torus: {
      s.extent_mm = {56, 56, 24};
      const Vec3 c(28.1, 27.8, 12.2);
      const double big = 16.0, small = 5.0;
      vessel([=](const Vec3& p) { return sd_torus_z(p, c, big, small); });
      s.seeds_mm = {c + Vec3(big, 0, 0)};
      s.analytic_volume_mm3 = 2.0 * kPi * kPi * big * small * small;
      s.description = "torus around z, radii 16 and 5 mm (genus 1)";
      break;
    }
    case PhantomKind::YBifurcation: {
      s.extent_mm = {48, 40, 58};
      const Vec3 a(24.1, 20.2, 6.0), fork(24.1, 20.2, 28.0);
      const Vec3 l(10.0, 20.2, 50.0), r(38.0, 20.2, 50.0);
      vessel([=](const Vec3& p) {
        return std::min({sd_capsule(p, a, fork, 5.0, 5.0), sd_capsule(p, fork, l, 4.0, 4.0),
                         sd_capsule(p, fork, r, 4.0, 4.0)});
      });
      s.seeds_mm = {Vec3(24.1, 20.2, 14.0)};
      s.description = "Y bifurcation: trunk r 5 mm, branches r 4 mm";
      break;
    }
    case PhantomKind::UTube: {
      s.extent_mm = {48, 32, 56};
      const double r = 5.0, bend = r;  // arms 2r apart: they touch along a line
      const double cx = 24.2, cy = 16.1, z0 = 10.0, z1 = 38.0;
      vessel([=](const Vec3& p) {
        const Vec3 la(cx - bend, cy, z0), lb(cx - bend, cy, z1);
        const Vec3 ra(cx + bend, cy, z0), rb(cx + bend, cy, z1);
        double d = std::min(sd_capsule(p, la, lb, r, r), sd_capsule(p, ra, rb, r, r));
        if (p.z() >= z1) {
          const double v = hypot2(p.x() - cx, p.z() - z1);
          d = std::min(d, hypot2(v - bend, p.y() - cy) - r);
        }
        return d;
      });
      s.seeds_mm = {Vec3(cx - bend, cy, 0.5 * (z0 + z1))};
      s.analytic_volume_mm3 = kPi * kPi * r * r * r + 2.0 * kPi * r * r * (z1 - z0) + 4.0 / 3.0 * kPi * r * r * r;
      s.description = "U tube r 5 mm, arms touching along a line (one genus-0 object)";
      break;
    }
    case PhantomKind::VesselNearBone: {
      s.extent_mm = {48, 40, 48};
      const double sx = o.spacing_mm.x(), sy = o.spacing_mm.y();
      const double rv = 5.0, rb = 8.0;
      // Voxel i spans [i·sx, (i+1)·sx]: the vessel ends on a voxel face and the bone starts
      // one voxel further, so exactly one column of pure soft tissue separates them.
      const double face = std::floor(21.0 / sx) * sx;
      const double xv = face - rv, xb = face + sx + rb;
      const double yc = (std::floor(20.0 / sy) + 0.5) * sy;
      vessel([=](const Vec3& p) { return sd_capsule(p, Vec3(xv, yc, 8.0), Vec3(xv, yc, 40.0), rv, rv); });
      s.layers.push_back({[=](const Vec3& p) { return sd_capsule(p, Vec3(xb, yc, 2.0), Vec3(xb, yc, 46.0), rb, rb); },
                          hu.cortical_hu, false, 2.0, hu.cancellous_hu});
      s.seeds_mm = {Vec3(xv, yc, 24.0)};
      s.analytic_volume_mm3 = kPi * rv * rv * 32.0 + 4.0 / 3.0 * kPi * rv * rv * rv;
      s.description = fmt::format("vessel r 5 mm beside a bone cylinder r 8 mm (cortex 2 mm), gap {:g} mm "
                                  "(one voxel) of soft tissue",
                                  sx);
      break;
    }
    case PhantomKind::VesselTree: {
      s.extent_mm = {56, 48, 66};
      const Vec3 root(28.1, 24.2, 5.0), fork(28.1, 24.2, 26.0);
      const Vec3 ea(16.0, 28.0, 44.0), eb(40.0, 20.0, 42.0);
      vessel([=](const Vec3& p) {
        return std::min({sd_capsule(p, root, fork, 6.0, 5.0), sd_capsule(p, fork, ea, 4.5, 3.5),
                         sd_capsule(p, fork, eb, 4.5, 3.5), sd_capsule(p, ea, Vec3(7.0, 33.0, 60.0), 3.0, 2.0),
                         sd_capsule(p, ea, Vec3(22.0, 38.0, 59.0), 3.0, 2.0),
                         sd_capsule(p, eb, Vec3(47.0, 14.0, 58.0), 3.0, 2.0)});
      });
      s.seeds_mm = {Vec3(28.1, 24.2, 12.0)};
      s.description = "tapering vessel tree: trunk 6-5 mm, branches 4.5-3.5 mm, twigs 3-2 mm";
      break;
    }
    case PhantomKind::Vertebra: {
      s.extent_mm = {64, 72, 40};
      const Vec3 body(32.1, 50.0, 20.1);
      s.layers.push_back({vertebra_sdf(Vec3::Zero()), hu.cortical_hu, true, 1.5, hu.cancellous_hu});
      s.seeds_mm = {body};
      s.drill_path_mm = pedicle_path(Vec3::Zero());
      s.object_hu = hu.cancellous_hu;
      s.description = "vertebra: body r 15 mm (cortex 1.5 mm, cancellous core), ring of pedicles and "
                      "lamina around an 8 mm canal, spinous and transverse processes (genus 1)";
      break;
    }
    case PhantomKind::SpineAorta: {
      // The vertebra of PhantomKind::Vertebra (label 2) with the abdominal aorta (label 1,
      // r 9 mm) running along z in front of it and to its left, 7.8 mm from the body.
      s.extent_mm = {84, 92, 44};
      const Vec3 shift(4.0, 0.0, 2.0);
      const Vec3 aorta_a(59.0, 72.0, 12.0), aorta_b(59.0, 72.0, 32.0);
      vessel([=](const Vec3& p) { return sd_capsule(p, aorta_a, aorta_b, 9.0, 9.0); });
      s.layers.push_back({vertebra_sdf(shift), hu.cortical_hu, 2, 1.5, hu.cancellous_hu});
      s.seeds_mm = {Vec3(59.0, 72.0, 22.0), Vec3(32.1, 50.0, 20.1) + shift};
      s.seed_labels = {1, 2};
      s.drill_path_mm = pedicle_path(shift);
      s.description = "vertebra (label 2, genus 1) beside the aorta (label 1, r 9 mm, 7.8 mm from the "
                      "vertebral body), with a pedicle-screw drill path";
      break;
    }
    case PhantomKind::CalcifiedVessel: {
      // Lumen r 6 mm along z (label 1) with four calcified plaques (r 2.5 mm balls of
      // cortical HU centred on its wall, label 1: the vessel's reference includes them), and a
      // bone cylinder (label 2) 2 mm beyond the wall on the side without plaque.
      s.extent_mm = {52, 40, 48};
      const double rv = 6.0, rp = 2.5;
      const Vec3 a(18.1, 20.2, 6.0), b(18.1, 20.2, 42.0);
      vessel([=](const Vec3& p) { return sd_capsule(p, a, b, rv, rv); });
      const std::array<std::pair<double, double>, 4> plaques = {{{14.0, 90.0}, {21.0, 160.0}, {28.0, 215.0}, {33.0, 270.0}}};
      for (const auto& [z, deg] : plaques) {
        const double t = deg * kPi / 180.0;
        const Vec3 c(a.x() + rv * std::cos(t), a.y() + rv * std::sin(t), z);
        s.layers.push_back({[=](const Vec3& p) { return sd_sphere(p, c, rp); }, hu.cortical_hu, 1, 0.0, 0.0});
      }
      const double xb = a.x() + rv + 2.0 + 7.0;
      s.layers.push_back({[=](const Vec3& p) { return sd_capsule(p, Vec3(xb, a.y(), 2.0), Vec3(xb, a.y(), 46.0), 7.0, 7.0); },
                          hu.cortical_hu, 2, 2.0, hu.cancellous_hu});
      s.seeds_mm = {Vec3(a.x(), a.y(), 24.0)};
      s.description = "vessel r 6 mm (label 1) with four calcified plaques r 2.5 mm on its wall (label 1) and a bone "
                      "cylinder r 7 mm (label 2) 2 mm beside it";
      break;
    }
    case PhantomKind::ValveChamber: {
      // Aortic root leaving the left ventricle: a vessel (r 6 mm, label 1) along z from z = 4
      // to the valve plane z = 44, where a soft-tissue ring (torus, tube r 1.5 mm on the
      // vessel wall) narrows the lumen to r 4.5 mm; beyond it an ellipsoidal chamber
      // (semi-axes 28, 25, 30 mm, centre 6 mm off the vessel's axis, floor cut flat at the
      // valve plane) of the same 350 HU, not labelled.
      s.extent_mm = {72, 72, 104};
      const double rv = 6.0, ring = 1.5, z_valve = 44.0, z_start = 4.0;
      const Vec3 axis(30.0, 36.0, 0.0), chamber(36.0, 36.0, 68.0), semi(28.0, 25.0, 30.0);
      s.layers.push_back({[=](const Vec3& p) {
                            return std::max(sd_ellipsoid_bound(p, chamber, semi), z_valve - p.z());
                          },
                          hu.vessel_hu, 0, 0.0, 0.0});
      const Vec3 mid(axis.x(), axis.y(), 0.5 * (z_start + z_valve));
      vessel([=](const Vec3& p) { return sd_cylinder_z(p, mid, rv, 0.5 * (z_valve - z_start)); });
      const Vec3 valve(axis.x(), axis.y(), z_valve);
      s.layers.push_back({[=](const Vec3& p) { return sd_torus_z(p, valve, rv, ring); }, hu.soft_tissue_hu, 0, 0.0, 0.0});
      s.seeds_mm = {Vec3(axis.x(), axis.y(), 14.0)};  // 30 mm below the valve plane
      // The cylinder less the quarter of the ring's tube inside it below the valve plane
      // (Pappus: area π·ring²/4 at centroid radius rv − 4·ring/(3π)).
      s.analytic_volume_mm3 = kPi * rv * rv * (z_valve - z_start) -
                              2.0 * kPi * (rv - 4.0 * ring / (3.0 * kPi)) * (kPi * ring * ring / 4.0);
      s.description = "vessel r 6 mm (label 1) through a valve ring (lumen r 4.5 mm) into an unlabelled "
                      "chamber (ellipsoid 28 x 25 x 30 mm) of the same grey level";
      break;
    }
    case PhantomKind::VeinInParenchyma: {
      // IVC behind the liver: a vein (r 10 mm, label 1) along z; a liver-like ellipsoid
      // (semi-axes 45, 35, 35 mm, not labelled) 15 HU darker whose surface passes 6 mm beyond
      // the vein's axis at mid-height, so there the vein is wrapped in parenchyma over about
      // 60 % of its circumference. The seed is where the vein runs clear of the liver.
      s.extent_mm = {110, 84, 110};
      s.object_hu = hu.vein_hu;
      const double rv = 10.0;
      const Vec3 a(22.0, 42.0, 14.0), b(22.0, 42.0, 96.0);
      const Vec3 liver(22.0 - 6.0 + 45.0, 42.0, 62.0), semi(45.0, 35.0, 35.0);
      s.layers.push_back({[=](const Vec3& p) { return sd_ellipsoid_bound(p, liver, semi); }, hu.parenchyma_hu, 0, 0.0, 0.0});
      s.layers.push_back({[=](const Vec3& p) { return sd_capsule(p, a, b, rv, rv); }, hu.vein_hu, 1, 0.0, 0.0});
      s.seeds_mm = {Vec3(a.x(), a.y(), 16.0)};  // 19 mm below the first contact with the liver
      s.analytic_volume_mm3 = kPi * rv * rv * (b - a).norm() + 4.0 / 3.0 * kPi * rv * rv * rv;
      s.description = fmt::format("vein r 10 mm, {:g} HU (label 1), partly embedded in an unlabelled liver-like "
                                  "ellipsoid (45 x 35 x 35 mm) of {:g} HU",
                                  hu.vein_hu, hu.parenchyma_hu);
      break;
    }
    case PhantomKind::VertebraStack: {
      // Three copies of the Vertebra phantom's vertebra 27.5 mm apart along z (24 mm bodies,
      // 3.5 mm discs of disc_hu), each with facet plates (facet_sdf). A cortical osteophyte
      // (capsule r 1.75 mm at the body's rim) bridges each disc: left rim below the middle
      // vertebra, front rim above it. Label 1 = the middle vertebra (painted last).
      s.extent_mm = {64, 72, 100};
      const double step = 27.5, reach = 0.5 * step + 3.0;
      const std::array<Vec3, 3> shift = {Vec3(0, 0, 4.0), Vec3(0, 0, 4.0 + step), Vec3(0, 0, 4.0 + 2.0 * step)};
      // A vertebra with its facets lies within reach mm of its mid-plane (z = 20.1 + shift):
      // beyond 8 mm more, the distance to that slab is a lower bound that spares the full SDF.
      const auto bone = [&](const Vec3& sh) {
        return [f = vertebra_sdf(sh), g = facet_sdf(sh, reach), z0 = 20.1 + sh.z(), reach](const Vec3& p) {
          const double slab = std::abs(p.z() - z0) - reach;
          return slab > 8.0 ? slab : std::min(f(p), g(p));
        };
      };
      for (int d = 0; d < 2; ++d) {
        const Vec3 mid(32.1, 50.0, 20.1 + shift[d].z() + 0.5 * step);
        s.layers.push_back({[=](const Vec3& p) { return sd_cylinder_z(p, mid, 15.0, 2.0); }, hu.disc_hu, 0, 0.0, 0.0});
      }
      s.layers.push_back({bone(shift[0]), hu.cortical_hu, 0, 1.5, hu.cancellous_hu});
      s.layers.push_back({bone(shift[2]), hu.cortical_hu, 0, 1.5, hu.cancellous_hu});
      const double gap_lo = 20.1 + shift[0].z() + 12.0, gap_hi = 20.1 + shift[1].z() + 12.0;  // lower end plates
      const Vec3 left_a(18.1, 50.0, gap_lo - 1.5), left_b(18.1, 50.0, gap_lo + step - 24.0 + 1.5);
      const Vec3 front_a(32.1, 64.0, gap_hi - 1.5), front_b(32.1, 64.0, gap_hi + step - 24.0 + 1.5);
      s.layers.push_back({[=](const Vec3& p) { return sd_capsule(p, left_a, left_b, 1.75, 1.75); }, hu.cortical_hu, 0, 0.0, 0.0});
      s.layers.push_back({[=](const Vec3& p) { return sd_capsule(p, front_a, front_b, 1.75, 1.75); }, hu.cortical_hu, 0, 0.0, 0.0});
      s.layers.push_back({bone(shift[1]), hu.cortical_hu, 1, 1.5, hu.cancellous_hu});
      s.seeds_mm = {Vec3(32.1, 50.0, 20.1) + shift[1]};
      s.drill_path_mm = pedicle_path(shift[1]);
      s.object_hu = hu.cancellous_hu;
      s.description = "three vertebrae along z (bodies r 15 x 24 mm, 3.5 mm discs of 80 HU) joined by a cortical "
                      "osteophyte across each disc and 0.8 mm facet-joint gaps; label 1 = the middle vertebra "
                      "(genus 1)";
      break;
    }
    case PhantomKind::LungSeed: {
      // Chest: a lung (ellipsoid, semi-axes 34, 30, 36 mm) in soft tissue, three vessels of
      // soft-tissue HU (r 2, 1.5, 1 mm) across it, and an airway (label 1, r 6 mm): a trachea
      // along z in the mediastinum, 8 mm clear of the lung, then a bronchus running 46° off
      // it into the lung, where air meets lung with no wall. Seed in the trachea.
      s.extent_mm = {96, 80, 100};
      s.object_hu = hu.air_hu;
      s.background_hu = hu.lung_hu;
      const Vec3 lung(54.0, 40.0, 44.0), semi(34.0, 30.0, 36.0);
      s.layers.push_back({[=](const Vec3& p) { return sd_ellipsoid_bound(p, lung, semi); }, hu.lung_hu, 0, 0.0, 0.0});
      const std::array<std::tuple<Vec3, Vec3, double>, 3> vessels = {{{Vec3(40, 22, 20), Vec3(75, 30, 60), 2.0},
                                                                      {Vec3(70, 56, 15), Vec3(45, 56, 65), 1.5},
                                                                      {Vec3(36, 52, 48), Vec3(80, 46, 34), 1.0}}};
      for (const auto& [va, vb, r] : vessels)
        s.layers.push_back({[a = va, b = vb, rad = r](const Vec3& p) { return sd_capsule(p, a, b, rad, rad); },
                            hu.soft_tissue_hu, 0, 0.0, 0.0});  // named captures: clang 14 cannot capture bindings
      const Vec3 top(16.0, 40.0, 92.0), carina(16.0, 40.0, 70.0), tip(58.0, 40.0, 30.0);
      s.layers.push_back({[=](const Vec3& p) { return std::min(sd_capsule(p, top, carina, 6.0, 6.0), sd_capsule(p, carina, tip, 6.0, 6.0)); },
                          hu.air_hu, 1, 0.0, 0.0});
      s.seeds_mm = {Vec3(16.0, 40.0, 84.0)};
      s.description = fmt::format("airway r 6 mm, {:g} HU (label 1): trachea in soft tissue, bronchus into an "
                                  "unlabelled lung (ellipsoid 34 x 30 x 36 mm) of {:g} HU with three vessels r 1-2 mm",
                                  hu.air_hu, hu.lung_hu);
      break;
    }
  }
  return s;
}

std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

double uniform01(std::uint64_t& state) {  // in (0, 1]
  return (double(splitmix64(state) >> 11) + 1.0) * (1.0 / 9007199254740992.0);
}

}  // namespace

const std::vector<PhantomKind>& all_phantom_kinds() {
  static const std::vector<PhantomKind> k = {PhantomKind::Sphere,         PhantomKind::Torus,
                                             PhantomKind::YBifurcation,   PhantomKind::UTube,
                                             PhantomKind::VesselNearBone, PhantomKind::VesselTree,
                                             PhantomKind::Vertebra};
  return k;
}

std::string_view phantom_kind_name(PhantomKind kind) {
  switch (kind) {
    case PhantomKind::Sphere: return "sphere";
    case PhantomKind::Torus: return "torus";
    case PhantomKind::YBifurcation: return "y-bifurcation";
    case PhantomKind::UTube: return "u-tube";
    case PhantomKind::VesselNearBone: return "vessel-near-bone";
    case PhantomKind::VesselTree: return "vessel-tree";
    case PhantomKind::Vertebra: return "vertebra";
    case PhantomKind::SpineAorta: return "spine-aorta";
    case PhantomKind::CalcifiedVessel: return "calcified-vessel";
    case PhantomKind::ValveChamber: return "valve-chamber";
    case PhantomKind::VeinInParenchyma: return "vein-in-parenchyma";
    case PhantomKind::VertebraStack: return "vertebra-stack";
    case PhantomKind::LungSeed: return "lung-seed";
  }
  return "unknown";
}

PhantomKind parse_phantom_kind(std::string_view name) {
  std::string n(name);
  for (char& c : n) c = c == '_' ? '-' : char(std::tolower(static_cast<unsigned char>(c)));
  std::string valid;
  std::vector<PhantomKind> kinds = all_phantom_kinds();
  for (PhantomKind k : {PhantomKind::SpineAorta, PhantomKind::CalcifiedVessel, PhantomKind::ValveChamber,
                        PhantomKind::VeinInParenchyma, PhantomKind::VertebraStack, PhantomKind::LungSeed})
    kinds.push_back(k);
  for (PhantomKind k : kinds) {
    if (n == phantom_kind_name(k)) return k;
    valid += (valid.empty() ? "" : ", ") + std::string(phantom_kind_name(k));
  }
  throw InvalidInput(fmt::format("unknown phantom kind '{}' (valid: {})", name, valid));
}

Phantom make_phantom(PhantomKind kind, const PhantomOptions& o) {
  for (int a = 0; a < 3; ++a)
    if (!(o.spacing_mm[a] > 0.0 && o.spacing_mm[a] <= 10.0))
      throw InvalidInput(fmt::format("phantom spacing must be in (0, 10] mm, got {}", o.spacing_mm[a]));
  if (!(o.noise_hu >= 0.0) || !std::isfinite(o.noise_hu))
    throw InvalidInput("phantom noise must be a finite number of HU >= 0");
  if (!(o.blur_voxels >= 0.0) || !(o.blur_voxels <= 20.0))
    throw InvalidInput("phantom blur must be between 0 and 20 voxels");
  if (o.supersampling < 1 || o.supersampling > 8) throw InvalidInput("phantom supersampling must be 1..8");

  const Scene scene = make_scene(kind, o);
  Index3 n;
  for (int a = 0; a < 3; ++a) n[a] = std::max<std::int64_t>(2, std::llround(scene.extent_mm[a] / o.spacing_mm[a]));
  const Vec3 origin = 0.5 * o.spacing_mm;
  Phantom ph;
  ph.kind = kind;
  ph.ct_hu = image::Volume<float>(n, o.spacing_mm, origin);
  ph.labels = ph.ct_hu.like<std::uint8_t>(0);
  const int ss = o.supersampling;
  // Lipschitz slack of the tapered capsules (slope ≤ 0.1) on top of the half-diagonal.
  const double half_diag = 0.5 * o.spacing_mm.norm() * 1.15;
  const std::int64_t nx = n[0], ny = n[1];
  parallel_for_ranges(
      static_cast<std::size_t>(n[1] * n[2]),
      [&](std::size_t b, std::size_t e) {
        for (std::size_t r = b; r < e; ++r) {
          const std::int64_t j = std::int64_t(r) % ny, k = std::int64_t(r) / ny;
          for (std::int64_t i = 0; i < nx; ++i) {
            const Vec3 c = ph.ct_hu.index_to_world(Vec3(double(i), double(j), double(k)));
            float value;
            std::uint8_t object;
            const Sample centre = classify(scene, o.intensities, c);
            if (ss == 1 || centre.boundary_mm > half_diag) {
              value = float(centre.hu);
              object = centre.label;
            } else {
              double sum = 0.0;
              int inside[3] = {0, 0, 0};
              for (int c3 = 0; c3 < ss; ++c3)
                for (int c2 = 0; c2 < ss; ++c2)
                  for (int c1 = 0; c1 < ss; ++c1) {
                    const Vec3 off((c1 + 0.5) / ss - 0.5, (c2 + 0.5) / ss - 0.5, (c3 + 0.5) / ss - 0.5);
                    const Sample smp = classify(scene, o.intensities, c + off.cwiseProduct(o.spacing_mm));
                    sum += smp.hu;
                    inside[std::min<int>(smp.label, 2)] += 1;
                  }
              value = float(sum / (ss * ss * ss));
              // More than half the samples; an exact tie (even ss) goes to the centre sample.
              const int all = ss * ss * ss;
              object = 0;
              for (std::uint8_t l = 1; l <= 2; ++l) {
                const int twice = 2 * inside[l];
                if (twice > all || (twice == all && centre.label == l)) object = l;
              }
            }
            ph.ct_hu(i, j, k) = value;
            ph.labels(i, j, k) = object;
          }
        }
      },
      o.threaded, 8);

  if (o.blur_voxels > 0.0)
    ph.ct_hu = image::gaussian_smooth(ph.ct_hu, Vec3(o.blur_voxels * o.spacing_mm), {.threaded = o.threaded});
  if (o.noise_hu > 0.0) {
    const std::size_t slice = static_cast<std::size_t>(nx * ny);
    parallel_for(
        static_cast<std::size_t>(n[2]),
        [&](std::size_t k) {
          std::uint64_t state = o.seed * 0xD1B54A32D192ED03ull + k * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull;
          float* p = ph.ct_hu.data().data() + k * slice;
          for (std::size_t m = 0; m < slice; m += 2) {
            // Box–Muller: two independent standard normals from two uniforms.
            const double u1 = uniform01(state), u2 = uniform01(state);
            const double rad = std::sqrt(-2.0 * std::log(u1));
            p[m] += float(o.noise_hu * rad * std::cos(2.0 * kPi * u2));
            if (m + 1 < slice) p[m + 1] += float(o.noise_hu * rad * std::sin(2.0 * kPi * u2));
          }
        },
        o.threaded, 1);
  }

  ph.seeds_mm = scene.seeds_mm;
  ph.seed_labels = scene.seed_labels.empty() ? std::vector<int>(scene.seeds_mm.size(), 1) : scene.seed_labels;
  ph.drill_path_mm = scene.drill_path_mm;
  for (const Vec3& sd : scene.seeds_mm) {
    const Vec3 idx = ph.ct_hu.world_to_index(sd);
    ph.seeds_voxel.push_back({std::llround(idx[0]), std::llround(idx[1]), std::llround(idx[2])});
  }
  ph.truth_euler_characteristic = static_cast<int>(mask_euler_characteristic(ph.labels));
  ph.object_hu = scene.object_hu;
  ph.background_hu = scene.background_hu;
  ph.contrast_hu = std::abs(scene.object_hu - scene.background_hu);
  ph.analytic_volume_mm3 = scene.analytic_volume_mm3;
  ph.description = fmt::format("{}: {}; object {:g} HU on {:g} HU", phantom_kind_name(kind), scene.description,
                               scene.object_hu, scene.background_hu);
  return ph;
}

}  // namespace ido::segment
