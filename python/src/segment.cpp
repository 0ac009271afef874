// SPDX-License-Identifier: Apache-2.0
// Balloon segmentation, phantoms and accuracy metrics seen from Python: ido.segment (one call),
// ido.Balloon (step by step, the paper's single-step API), ido.phantom, ido.surface_to_mask,
// ido.compare, ido.compare_mesh. Options mirror `ido segment`'s flags.
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "ido/core/error.h"
#include "ido/segment/balloon.h"
#include "ido/segment/calcification.h"
#include "ido/segment/metrics.h"
#include "ido/segment/organ.h"
#include "ido/segment/phantom.h"

namespace py = pybind11;

namespace ido::python {
namespace {

using segment::BalloonOptions;
using segment::BalloonReport;
using segment::BalloonResult;

/// The keyword arguments shared by ido.segment and ido.Balloon.
struct SegmentArgs {
  std::optional<double> reference, tolerance;
  std::optional<std::array<double, 6>> roi;
  bool bone = false, white_noise = false;
  double edge_reach_voxels = 0.0;
  int max_iterations = 4000;
  std::optional<double> outside_level;
  std::string organ = "generic";
  std::vector<Vec3> stop_points;
  std::optional<double> max_radius_mm;
  bool leak_control = true;
};

// Python's keywords are the library's field names (reference, edge_reach_voxels, ...), so
// segment::balloon_options names them in its errors as they are.
BalloonOptions balloon_options(const SegmentArgs& a) {
  std::optional<geometry::Aabb> roi;
  if (a.roi) {
    const auto& r = *a.roi;
    roi = geometry::Aabb{Vec3(r[0], r[1], r[2]), Vec3(r[3], r[4], r[5])};
  }
  return segment::balloon_options({.organ = segment::parse_organ(a.organ),
                                   .reference = a.reference,
                                   .tolerance = a.tolerance,
                                   .bone = a.bone,
                                   .white_noise = a.white_noise,
                                   .edge_reach_voxels = a.edge_reach_voxels,
                                   .outside_level = a.outside_level,
                                   .max_iterations = a.max_iterations,
                                   .roi_mm = roi,
                                   .leak_control = a.leak_control,
                                   .stop_points_mm = a.stop_points,
                                   .max_radius_mm = a.max_radius_mm});
}

/// World seeds from @p seeds (mm) and @p seed_voxels (voxel indices of @p ct).
std::vector<Vec3> seed_points(const image::Volume<float>& ct, const std::vector<Vec3>& seeds,
                              const std::vector<std::array<std::int64_t, 3>>& seed_voxels) {
  std::vector<Vec3> out = seeds;
  for (const auto& v : seed_voxels) {
    if (!ct.contains(v[0], v[1], v[2]))
      throw InvalidInput("seed voxel (" + std::to_string(v[0]) + ", " + std::to_string(v[1]) + ", " +
                         std::to_string(v[2]) + ") lies outside the " + std::to_string(ct.size(0)) + "x" +
                         std::to_string(ct.size(1)) + "x" + std::to_string(ct.size(2)) + " volume");
    out.push_back(ct.index_to_world(Vec3(double(v[0]), double(v[1]), double(v[2]))));
  }
  if (out.empty()) throw InvalidInput("give at least one seed (seeds in mm or seed_voxels)");
  return out;
}

}  // namespace

void bind_segment(py::module_& m) {
  py::class_<BalloonResult>(m, "Segmentation", "What ido.segment / Balloon.run produced: a surface and a report.")
      .def_readonly("surface", &BalloonResult::surface, "The closed, manifold surface (ido.TriangleMesh, mm).")
      .def("__repr__",
           [](const BalloonResult& r) {
             return fmt::format("<ido.Segmentation {} vertices, {} triangles, volume {:.1f} mm3, Euler {}, {}>",
                                r.report.vertices, r.report.triangles, r.report.volume_mm3,
                                r.report.euler_characteristic, r.report.stop_reason);
           })
      .def_property_readonly(
          "report", [](const BalloonResult& r) { return to_python(io::to_json(r.report)); },
          "Reference and tolerance used, iterations, seconds (and per phase), volume, area, V/E/F, Euler "
          "characteristic, closed / manifold / oriented flags, self-intersections (0), repairs, stop reason, leak "
          "warning.");

  const char* seg_doc =
      "Balloon segmentation (Turini et al. 2007): an icosphere at each seed inflated until it fits the wall, "
      "refined to voxel size, self-intersections repaired so the surface takes the organ's topology. seeds: "
      "world points (mm, LPS); seed_voxels: (i, j, k) indices. reference and tolerance (image units) are "
      "estimated at the seeds when not given. roi = (x0, y0, z0, x1, y1, z1) mm is a safeguard box; bone "
      "accepts anything brighter than the reference; edge_reach_voxels bounds the final snap to the wall "
      "(0 = no limit); outside_level is the level of the tissue bounding the organ (e.g. 40 HU for a vessel's "
      "wall: the surface follows the lumen where lung or fat lies beyond the wall); calcium adds plaque "
      "brighter than it within calcium_reach_mm of the lumen. organ: generic, artery, vein or vertebra (settings "
      "in docs/segmentation.md). Leak control (on unless leak_control=False): the front may not enter a "
      "chamber wider than 2.5x the seed region's radius; stop_points (mm) close the band within 1.5x the local "
      "radius of each; max_radius_mm closes wherever a ball that wide fits. The report lists each leak stopped. Releases the GIL while it runs. Raises "
      "ValueError for bad input.";
  m.def(
      "segment",
      [](const image::Volume<float>& ct, const std::vector<Vec3>& seeds,
         const std::vector<std::array<std::int64_t, 3>>& seed_voxels, std::optional<double> reference,
         std::optional<double> tolerance, std::optional<std::array<double, 6>> roi, bool bone, bool white_noise,
         double edge_reach_voxels, int max_iterations, std::optional<double> calcium, double calcium_reach_mm,
         std::optional<double> outside_level, const std::string& organ, const std::vector<Vec3>& stop_points,
         std::optional<double> max_radius_mm, bool leak_control) {
        const SegmentArgs a{reference,     tolerance,    roi,         bone,          white_noise, edge_reach_voxels,
                            max_iterations, outside_level, organ,      stop_points,   max_radius_mm, leak_control};
        const BalloonOptions bo = balloon_options(a);
        const std::vector<Vec3> points = seed_points(ct, seeds, seed_voxels);
        py::gil_scoped_release unlocked;
        BalloonResult r = segment::segment_balloon(ct, points, bo);
        if (calcium) (void)segment::add_calcification(r, ct, {.threshold = *calcium, .max_reach_mm = calcium_reach_mm});
        return r;
      },
      py::arg("ct"), py::arg("seeds") = std::vector<Vec3>{},
      py::arg("seed_voxels") = std::vector<std::array<std::int64_t, 3>>{}, py::kw_only(),
      py::arg("reference") = py::none(), py::arg("tolerance") = py::none(), py::arg("roi") = py::none(),
      py::arg("bone") = false, py::arg("white_noise") = false, py::arg("edge_reach_voxels") = 0.0,
      py::arg("max_iterations") = 4000, py::arg("calcium") = py::none(), py::arg("calcium_reach_mm") = 4.0,
      py::arg("outside_level") = py::none(), py::arg("organ") = "generic",
      py::arg("stop_points") = std::vector<Vec3>{}, py::arg("max_radius_mm") = py::none(),
      py::arg("leak_control") = true, seg_doc);

  py::class_<segment::Balloon>(m, "Balloon",
                               "The balloon driven step by step: step() inflates once, surface shows the current "
                               "mesh, run() finishes (edge stage and final repair). Same arguments as ido.segment "
                               "without calcium.")
      .def("__repr__",
           [](const segment::Balloon& b) {
             return fmt::format("<ido.Balloon {} vertices, reference {:g}, tolerance {:g}>", b.particles().size(),
                                b.model().reference, b.model().tolerance);
           })
      .def(py::init([](const image::Volume<float>& ct, const std::vector<Vec3>& seeds,
                       const std::vector<std::array<std::int64_t, 3>>& seed_voxels, std::optional<double> reference,
                       std::optional<double> tolerance, std::optional<std::array<double, 6>> roi, bool bone,
                       bool white_noise, double edge_reach_voxels, int max_iterations,
                       std::optional<double> outside_level, const std::string& organ,
                       const std::vector<Vec3>& stop_points, std::optional<double> max_radius_mm, bool leak_control) {
             const SegmentArgs a{reference,      tolerance,     roi,   bone,        white_noise,   edge_reach_voxels,
                                 max_iterations, outside_level, organ, stop_points, max_radius_mm, leak_control};
             const BalloonOptions bo = balloon_options(a);
             const std::vector<Vec3> points = seed_points(ct, seeds, seed_voxels);
             py::gil_scoped_release unlocked;
             return segment::Balloon(ct, points, bo);
           }),
           py::arg("ct"), py::arg("seeds") = std::vector<Vec3>{},
           py::arg("seed_voxels") = std::vector<std::array<std::int64_t, 3>>{}, py::kw_only(),
           py::arg("reference") = py::none(), py::arg("tolerance") = py::none(), py::arg("roi") = py::none(),
           py::arg("bone") = false, py::arg("white_noise") = false, py::arg("edge_reach_voxels") = 0.0,
           py::arg("max_iterations") = 4000, py::arg("outside_level") = py::none(), py::arg("organ") = "generic",
           py::arg("stop_points") = std::vector<Vec3>{}, py::arg("max_radius_mm") = py::none(),
           py::arg("leak_control") = true)
      .def(
          "step",
          [](segment::Balloon& b) {
            py::gil_scoped_release unlocked;
            return b.step();
          },
          "One inflation step; True once converged or stopped by a safeguard.")
      .def(
          "run",
          [](segment::Balloon& b) {
            py::gil_scoped_release unlocked;
            return b.run();
          },
          "Steps until done, then the edge stage and the final repair; returns an ido.Segmentation.")
      .def_property_readonly("surface", &segment::Balloon::surface, "The current surface (a copy).")
      .def_property_readonly(
          "reference", [](const segment::Balloon& b) { return b.model().reference; }, "The reference in use.")
      .def_property_readonly(
          "tolerance", [](const segment::Balloon& b) { return b.model().tolerance; }, "The tolerance in use.");

  py::class_<segment::Phantom>(m, "Phantom", "A synthetic CT (HU) with its ground truth, seeds and known topology.")
      .def("__repr__",
           [](const segment::Phantom& p) {
             const auto n = p.ct_hu.size();
             return fmt::format("<ido.Phantom {} {}x{}x{}, {} seed(s)>", segment::phantom_kind_name(p.kind), n[0], n[1],
                                n[2], p.seeds_mm.size());
           })
      .def_property_readonly(
          "kind", [](const segment::Phantom& p) { return std::string(segment::phantom_kind_name(p.kind)); })
      .def_readonly("ct", &segment::Phantom::ct_hu, "The CT-like volume (ido.Volume, HU).")
      .def_readonly("labels", &segment::Phantom::labels, "The ground truth (ido.Mask on the same grid).")
      .def_readonly("seeds", &segment::Phantom::seeds_mm, "Seed points inside the object (world mm).")
      .def_readonly("seed_labels", &segment::Phantom::seed_labels, "The label each seed lies in.")
      .def_readonly("truth_euler_characteristic", &segment::Phantom::truth_euler_characteristic)
      .def_readonly("object_hu", &segment::Phantom::object_hu)
      .def_readonly("background_hu", &segment::Phantom::background_hu)
      .def_readonly("contrast_hu", &segment::Phantom::contrast_hu)
      .def_readonly("analytic_volume_mm3", &segment::Phantom::analytic_volume_mm3, "0 where no closed form is known.")
      .def_readonly("description", &segment::Phantom::description);

  m.def(
      "phantom_kinds",
      [] {
        std::vector<std::string> names;
        for (auto k : segment::all_phantom_kinds()) names.emplace_back(segment::phantom_kind_name(k));
        return names;
      },
      "The names ido.phantom accepts.");
  m.def(
      "phantom",
      [](const std::string& kind, double noise_hu, double blur_voxels, const Vec3& spacing, std::uint64_t seed) {
        const segment::PhantomKind k = segment::parse_phantom_kind(kind);
        py::gil_scoped_release unlocked;
        return segment::make_phantom(
            k, {.spacing_mm = spacing, .noise_hu = noise_hu, .blur_voxels = blur_voxels, .seed = seed});
      },
      py::arg("kind"), py::kw_only(), py::arg("noise_hu") = 0.0, py::arg("blur_voxels") = 0.0,
      py::arg("spacing") = Vec3(Vec3::Ones()), py::arg("seed") = 1,
      "A synthetic CT with ground truth (see phantom_kinds()); deterministic for a seed.");

  m.def(
      "surface_to_mask",
      [](const geometry::TriangleMesh& surface, const image::Volume<float>& like) {
        py::gil_scoped_release unlocked;
        return segment::surface_to_mask(surface, like);
      },
      py::arg("surface"), py::arg("like"),
      "The mask (1 inside, generalised winding number > 1/2 at the voxel centre) of a closed surface on the grid "
      "of `like`.");
  m.def(
      "compare",
      [](const image::Volume<std::uint8_t>& mask, const image::Volume<std::uint8_t>& truth) {
        segment::SegmentationScores s;
        {
          py::gil_scoped_release unlocked;
          s = segment::compare_masks(mask, truth);
        }
        return to_python(io::to_json(s));
      },
      py::arg("mask"), py::arg("truth"),
      "Dice, HD95, ASSD and Hausdorff distance (mm, both directions, spacing-aware), volume ratio and 6-connected "
      "components of a mask against a truth, as a dict (definitions: docs/metrics.md). A mask on another grid is "
      "resampled onto the truth's in physical space.");
  m.def(
      "compare_mesh",
      [](const geometry::TriangleMesh& surface, const image::Volume<std::uint8_t>& truth) {
        segment::SegmentationScores s;
        {
          py::gil_scoped_release unlocked;
          s = segment::compare_mesh_to_mask(surface, truth);
        }
        return to_python(io::to_json(s));
      },
      py::arg("surface"), py::arg("truth"), "compare() for a closed surface, rasterised onto the truth's grid.");
}

}  // namespace ido::python
