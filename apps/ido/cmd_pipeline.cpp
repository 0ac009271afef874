// SPDX-License-Identifier: Apache-2.0
// `ido pipeline CT --seed ... -o OUTDIR`: the paper's chain in one run. Segment a vessel (and
// optionally a bone) with the balloon, mesh the bone (or the vessel) with tetrahedra, drill a
// scripted path with density from the CT, deform the vessel segment, and write every stage's
// files, pictures, a report.json and a summary.md. Orchestration only: every step is a
// library call.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_util.h"
#include "command.h"
#include "energy_plot.h"
#include "drill_report.h"
#include "ido/core/error.h"
#include "ido/core/log.h"
#include "ido/drill/boundary_surface.h"
#include "ido/drill/embedding.h"
#include "ido/drill/haptic_device.h"
#include "ido/drill/simulator.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/drill/tool.h"
#include "ido/geometry/aabb.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/tet_quality.h"
#include "ido/io/mesh_io.h"
#include "ido/io/report_json.h"
#include "ido/io/scene.h"
#include "ido/io/volume_io.h"
#include "ido/meshing/distance_field.h"
#include "ido/meshing/tetrahedralize.h"
#include "ido/segment/balloon.h"
#include "ido/segment/metrics.h"
#include "ido/segment/organ.h"
#include "ido/sim/fem_corotational.h"
#include "ido/viz/renderer.h"

namespace ido::cli {
namespace {
namespace fs = std::filesystem;
using json = io::Json;

struct Options {
  std::string ct;
  std::vector<std::string> seeds, seed_voxels, bone_seeds, bone_seed_voxels;
  std::string out_dir;
  std::string drill_path;
  std::string scene;
  bool deform = false;
  std::string tool = "sphere:radius=2";
  int max_depth = 3;
  double edge_mm = 0.0;
  std::string truth;
  // The vessel's balloon, as `ido segment` takes it (--reference, --tolerance, --edge-reach,
  // --outside-level); the box bounds both organs.
  std::optional<double> vessel_reference, vessel_tolerance, vessel_outside_level;
  double vessel_edge_reach = 0.0;
  std::string vessel_organ = "generic";
  std::string roi;
  int vessel_label = 1;
  int bone_label = 2;
  double deform_steps = 60;
};

/// Everything one segmented organ produced.
struct Organ {
  std::string name;
  segment::BalloonResult balloon;
  image::Volume<std::uint8_t> mask;
};

std::vector<Vec3> collect_seeds(const std::vector<std::string>& world, const std::vector<std::string>& voxel,
                                const image::Volume<float>& ct, const char* flag_world, const char* flag_voxel) {
  std::vector<Vec3> seeds;
  for (const auto& s : world) seeds.push_back(parse_vec3(s, flag_world));
  for (const auto& s : voxel) {
    const Index3 idx = parse_index3(s, flag_voxel);
    if (!ct.contains(idx[0], idx[1], idx[2]))
      throw InvalidInput(fmt::format("{} {}: voxel outside the {}x{}x{} volume", flag_voxel, s, ct.size(0),
                                     ct.size(1), ct.size(2)));
    seeds.push_back(ct.index_to_world(Vec3(double(idx[0]), double(idx[1]), double(idx[2]))));
  }
  return seeds;
}

image::Volume<std::uint8_t> label_mask(const image::Volume<float>& labels, int label) {
  auto mask = labels.like<std::uint8_t>(0);
  for (std::size_t i = 0; i < labels.voxel_count(); ++i)
    mask.data()[i] = std::lround(labels.data()[i]) == label ? 1 : 0;
  return mask;
}

Organ segment_organ(const std::string& name, const image::Volume<float>& ct, const std::vector<Vec3>& seeds,
                    const segment::BalloonOptions& bo, const fs::path& dir, Progress* progress) {
  Organ organ{name, segment::segment_balloon(ct, seeds, bo, progress), {}};
  organ.mask = segment::surface_to_mask(organ.balloon.surface, ct);
  io::write_triangle_mesh(dir / (name + "_surface.stl"), organ.balloon.surface);
  io::write_volume(dir / (name + "_mask.nii.gz"), organ.mask);
  return organ;
}

/// Axial slice through @p point with each organ's contour, and a 3D view of the surfaces.
void organ_pictures(const image::Volume<float>& ct, const std::vector<const Organ*>& organs, const Vec3& point,
                    const fs::path& dir, json& pictures) {
  const Vec3 idx = ct.world_to_index(point);
  const auto k = std::clamp<std::int64_t>(std::llround(idx.z()), 0, ct.size(2) - 1);
  const std::array<Vec3, 3> colours = {Vec3(1, 0.15, 0.1), Vec3(0.1, 0.8, 1.0), Vec3(1, 0.9, 0.1)};
  {
    viz::Renderer r(768, 768);
    r.add_slice(ct, 2, k, {.window = 1200, .level = 200});
    for (std::size_t i = 0; i < organs.size(); ++i) r.add_contour(organs[i]->mask, 2, k, colours[i % 3]);
    r.set_camera(r.slice_camera(0));
    r.write_png(dir / "ct_slice_contours.png");
    pictures.push_back(json{{"file", "ct_slice_contours.png"},
                            {"what", fmt::format("CT slice k={} with the segmentation contours", k)}});
  }
  {
    viz::Renderer r(900, 700);
    const std::array<Vec3, 3> surface_colours = {Vec3(0.85, 0.25, 0.2), Vec3(0.92, 0.88, 0.78), Vec3(0.4, 0.7, 0.9)};
    for (std::size_t i = 0; i < organs.size(); ++i) r.add_surface(organs[i]->balloon.surface, surface_colours[i % 3]);
    r.set_camera(r.fit_camera(30, 20));
    r.write_png(dir / "surfaces.png");
    pictures.push_back(json{{"file", "surfaces.png"}, {"what", "segmented surfaces"}});
  }
}

geometry::TetMesh mesh_organ(const Organ& organ, double edge_mm, Progress* progress) {
  const auto sdf = meshing::signed_distance_from_mask(organ.mask);
  return meshing::tetrahedralize(sdf, {.edge_mm = edge_mm}, progress);
}

/// The plane through the tool path's centroid that best holds the path (least variance of its
/// positions along the normal); for a straight path, the plane through it most nearly
/// horizontal. The normal points up (+z), or along +x when the plane is vertical.
viz::ClipPlane plane_along_path(const drill::ScriptedTrajectory& device) {
  constexpr int kSamples = 64;
  std::vector<Vec3> p;
  for (int k = 0; k <= kSamples; ++k) p.push_back(device.pose_at(device.duration() * k / kSamples).position_mm);
  Vec3 c = Vec3::Zero();
  for (const Vec3& q : p) c += q / double(p.size());
  Mat3 cov = Mat3::Zero();
  for (const Vec3& q : p) cov += (q - c) * (q - c).transpose();
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(cov);
  const Vec3 ev = eig.eigenvalues();
  Vec3 n = eig.eigenvectors().col(0);
  if (ev[1] <= 1e-9 * std::max(ev[2], 1e-300)) {
    // Collinear (or a single point): the plane through the line closest to horizontal.
    const Vec3 d = ev[2] > 0 ? Vec3(eig.eigenvectors().col(2)) : Vec3(1, 0, 0);
    n = Vec3::UnitZ() - Vec3::UnitZ().dot(d) * d;
    if (n.norm() < 1e-9) n = Vec3::UnitX();
  }
  n.normalize();
  if (n.z() < -1e-12 || (std::abs(n.z()) <= 1e-12 && n.x() < 0)) n = -n;
  return {.point = c, .normal = n};
}

json run_drill(const Options& o, const geometry::TetMesh& mesh, const image::Volume<float>& ct, const fs::path& dir,
               json& pictures) {
  drill::SimulatorOptions so;
  so.tool = drill::parse_tool(o.tool);
  so.erosion.max_depth = o.max_depth;
  auto device = drill::ScriptedTrajectory::load_csv(o.drill_path);
  drill::TetHierarchy hierarchy(mesh);
  drill::assign_density_from_ct(hierarchy, ct);
  const double before = hierarchy.material_volume();
  drill::Simulator sim(hierarchy, device, so);
  sim.run(device.duration() + 60.0);
  const auto leaves = drill::full_leaf_mesh(hierarchy);
  io::write_tet_mesh(dir / "drilled.vtu", leaves);
  const auto surface = drill::assemble_surface(sim.render_v_lists(), hierarchy.vertices());
  io::write_triangle_mesh(dir / "drilled_surface.stl", surface);
  json r = drill_session_json(hierarchy, sim, so, before);
  r["path"] = o.drill_path;
  r["surface_checks"] = io::to_json(geometry::check_mesh(surface));

  // Picture: the drilled mesh cut by the plane that best holds the tool path, seen face on and
  // coloured by refinement depth, so the whole channel shows as the refined band.
  const viz::ClipPlane cut = plane_along_path(device);
  viz::Renderer pic(900, 700);
  pic.add_tet_mesh_clipped(leaves, cut, "depth");
  const double elevation = std::asin(std::clamp(cut.normal.z(), -1.0, 1.0)) * 180.0 / kPi;
  const double azimuth = std::atan2(cut.normal.x(), -cut.normal.y()) * 180.0 / kPi;
  pic.set_camera(pic.fit_camera(azimuth, std::clamp(elevation, -89.0, 89.0)));
  pic.write_png(dir / "drilled_clip.png");
  pictures.push_back(json{{"file", "drilled_clip.png"},
                          {"what", "drilled mesh cut along the tool path, coloured by refinement depth (the channel)"}});
  return r;
}

/// A short deformation of @p mesh: corotational FEM, implicit Euler, the lowest 15 % (along
/// z) clamped, sagging under gravity along −y. The world is built in memory and stepped by the
/// library's run loop (io::run_scene's writer observer puts the frames, energies and report in
/// deformation/); the same scene is also written as deformation/scene.json + body.vtu so that
/// `ido simulate` re-runs it, but nothing is read back.
json run_deformation(const geometry::TetMesh& mesh, const fs::path& dir, int steps, json& pictures,
                     Progress* progress) {
  const fs::path sim_dir = dir / "deformation";
  fs::create_directories(sim_dir);
  const geometry::Aabb box = geometry::Aabb::of(mesh.vertices);
  const Vec3 &lo = box.min, &hi = box.max;
  const double clamp_z = lo.z() + 0.15 * (hi.z() - lo.z());
  const Vec3 fixed_min(lo.x() - 1, lo.y() - 1, lo.z() - 1), fixed_max(hi.x() + 1, hi.y() + 1, clamp_z);
  constexpr double kDt = 0.01, kRayleighMass = 1.0, kGravityY = -9806.65;   // s, 1/s, mm/s² (along y)
  constexpr int kDensity = 1060;   // kg/m³
  const sim::ElasticMaterial material{.youngs_modulus_pa = 5e4, .poisson_ratio = 0.45};
  const int output_every = std::max(1, steps / 10);

  io::Scene scene;
  scene.source = (sim_dir / "scene.json").string();
  scene.dt_s = kDt;
  scene.steps = steps;
  scene.output_every = output_every;
  auto& world = scene.world;
  world.set_integrator("implicit_euler");
  world.implicit_options().cg_tolerance = 1e-6;
  world.implicit_options().cg_max_iterations = 300;
  world.external().gravity_mm_s2 = Vec3(0, kGravityY, 0);
  world.external().damping.mass_per_s = kRayleighMass;
  io::SceneBody body;
  body.name = "vessel";
  body.rest_mesh = mesh;
  body.material = material;
  body.first_particle = world.add_tet_body(mesh, kDensity);
  world.emplace_model<sim::CorotationalFem>(mesh.tets, world.particles().positions(), material);
  body.model_index = body.stress_model_index = world.models().size() - 1;
  const geometry::Aabb clamp{fixed_min, fixed_max};
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    if (clamp.contains(mesh.vertices[i])) world.particles().set_fixed(i, true);
  scene.bodies.push_back(std::move(body));

  // The same scene as a file, for `ido simulate`.
  io::write_tet_mesh(sim_dir / "body.vtu", mesh);
  const json scene_json = {
      {"description", "pipeline: the segmented vessel, clamped at its lower end, sagging under gravity"},
      {"dt_s", kDt},
      {"steps", steps},
      {"output_every", output_every},
      {"integrator", "implicit_euler"},
      {"implicit", {{"cg_tolerance", 1e-6}, {"cg_max_iterations", 300}}},
      {"gravity_mm_s2", {0, kGravityY, 0}},
      {"damping", {{"rayleigh_mass_per_s", kRayleighMass}, {"rayleigh_stiffness_s", 0.0}}},
      {"bodies",
       {{{"name", "vessel"},
         {"mesh", {{"file", "body.vtu"}}},
         {"model", "corotational_fem"},
         {"material", {{"youngs_modulus_pa", material.youngs_modulus_pa},
                       {"poisson_ratio", material.poisson_ratio},
                       {"density_kg_m3", kDensity}}},
         {"fixed", {{{"box_min_mm", {fixed_min.x(), fixed_min.y(), fixed_min.z()}},
                     {"box_max_mm", {fixed_max.x(), fixed_max.y(), fixed_max.z()}}}}}}}}};
  write_text_file((sim_dir / "scene.json").string(), scene_json.dump(2) + "\n");

  const auto result = io::run_scene(scene, sim_dir, progress);
  write_energy_plot(sim_dir / "energy.png", result);
  pictures.push_back(json{{"file", "deformation/energy.png"}, {"what", "energy of the deforming vessel over time"}});
  std::vector<double> ms = result.step_ms;
  std::sort(ms.begin(), ms.end());
  return {{"scene", "deformation/scene.json"},
          {"steps", steps},
          {"frames", result.frames},
          {"wall_time_s", result.wall_time_s},
          {"ms_per_step_p50", ms.empty() ? 0.0 : ms[ms.size() / 2]},
          {"final_energy", io::to_json(result.final_energy)}};
}

json run_user_scene(const std::string& scene_path, const fs::path& dir, Progress* progress) {
  const fs::path sim_dir = dir / "simulation";
  fs::create_directories(sim_dir);
  auto scene = io::load_scene(scene_path);
  const auto result = io::run_scene(scene, sim_dir, progress);
  return {{"scene", scene_path}, {"frames", result.frames}, {"wall_time_s", result.wall_time_s},
          {"final_energy", io::to_json(result.final_energy)}};
}

std::string summary_markdown(const json& report) {
  std::string md = "# ido pipeline summary\n\n";
  md += fmt::format("Input: `{}`\n\n", report["input"].get<std::string>());
  md += "| stage | figures |\n|---|---|\n";
  for (const auto& [name, organ] : report["segmentation"].items()) {
    std::string fig = fmt::format("volume {:.0f} mm³, {} triangles, Euler {}, closed {}, self-intersections {}, {:.1f} s",
                                  organ["balloon"]["volume_mm3"].get<double>(),
                                  organ["balloon"]["triangles"].get<std::int64_t>(),
                                  organ["balloon"]["euler_characteristic"].get<std::int64_t>(),
                                  organ["balloon"]["closed"].get<bool>(),
                                  organ["balloon"]["self_intersections"].get<std::int64_t>(),
                                  organ["balloon"]["seconds"].get<double>());
    if (organ.contains("scores"))
      fig += fmt::format("; Dice {:.3f}, HD95 {:.2f} mm", organ["scores"]["dice"].get<double>(),
                         organ["scores"]["hd95_mm"].get<double>());
    md += fmt::format("| segment {} | {} |\n", name, fig);
  }
  if (report.contains("tetmesh")) {
    const auto& t = report["tetmesh"];
    md += fmt::format("| tetrahedral mesh ({}) | {} tets, volume {:.0f} mm³, dihedral {:.1f}°–{:.1f}°, inverted {} |\n",
                      t["organ"].get<std::string>(), t["quality"]["tets"].get<std::size_t>(),
                      t["quality"]["volume_mm3"].get<double>(), t["quality"]["min_dihedral_deg"].get<double>(),
                      t["quality"]["max_dihedral_deg"].get<double>(), t["quality"]["inverted"].get<std::size_t>());
  }
  if (report.contains("drill")) {
    const auto& d = report["drill"];
    md += fmt::format("| drill | removed {:.1f} mm³, remaining {:.0f} mm³, {} nodes at {:.1f} B/node, update p50 {:.2f} ms |\n",
                      d["removed_volume_mm3"].get<double>(), d["remaining_volume_mm3"].get<double>(),
                      d["node_count"].get<std::size_t>(), d["bytes_per_node"].get<double>(),
                      d["update_time_ms"]["p50"].get<double>());
  }
  if (report.contains("deformation")) {
    const auto& d = report["deformation"];
    md += fmt::format("| deformation | {} steps, {:.1f} ms/step (p50), final elastic energy {:.4g} mJ |\n",
                      d["steps"].get<int>(), d["ms_per_step_p50"].get<double>(),
                      d["final_energy"]["elastic_mj"].get<double>());
  }
  md += "\n## Pictures\n\n";
  for (const auto& p : report["pictures"])
    md += fmt::format("![{}]({})\n\n", p["what"].get<std::string>(), p["file"].get<std::string>());
  md += "## Files\n\n";
  for (const auto& f : report["files"]) md += fmt::format("- `{}`\n", f.get<std::string>());
  return md;
}

void run(const Options& o, const GlobalOptions& g) {
  const auto start = std::chrono::steady_clock::now();
  const segment::Organ vessel_organ = parse_organ_option(o.vessel_organ, "--vessel-organ");
  if (vessel_organ == segment::Organ::Vertebra) throw InvalidInput("--vessel-organ: vertebra is for --bone-seed, not a vessel");
  std::optional<geometry::Aabb> roi;
  if (!o.roi.empty()) roi = parse_roi(o.roi);
  // The vessel takes --vessel-organ and the --vessel- options; the bone is a vertebra (kept apart
  // from its neighbours); the box bounds both.
  segment::BalloonChoices vessel_choices, bone_choices;
  vessel_choices.organ = vessel_organ;
  vessel_choices.reference = o.vessel_reference;
  vessel_choices.tolerance = o.vessel_tolerance;
  vessel_choices.edge_reach_voxels = o.vessel_edge_reach;
  vessel_choices.outside_level = o.vessel_outside_level;
  vessel_choices.roi_mm = bone_choices.roi_mm = roi;
  bone_choices.organ = segment::Organ::Vertebra;
  const segment::BalloonOptions vessel_options = balloon_options_from_flags("--vessel-", vessel_choices);
  const segment::BalloonOptions bone_options = balloon_options_from_flags("--", bone_choices);
  const fs::path dir = o.out_dir;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) throw IoError(o.out_dir, "cannot create the output folder");
  if (!o.drill_path.empty() && !fs::is_regular_file(o.drill_path))
    throw IoError(o.drill_path, "--drill-path: no such file");
  auto progress = make_progress(g.quiet);
  const auto ct = io::read_volume(o.ct);
  const auto vessel_seeds = collect_seeds(o.seeds, o.seed_voxels, ct, "--seed", "--seed-voxel");
  const auto bone_seeds = collect_seeds(o.bone_seeds, o.bone_seed_voxels, ct, "--bone-seed", "--bone-seed-voxel");
  if (vessel_seeds.empty() && bone_seeds.empty())
    throw InvalidInput("give at least one --seed (vessel) or --bone-seed (bone)");
  std::optional<image::Volume<float>> truth;
  if (!o.truth.empty()) truth = io::read_volume(o.truth);

  json report;
  report["input"] = o.ct;
  // The lists are kept apart until the end: report's keys live in a vector, so a reference
  // into it would move as keys are added.
  json pictures = json::array(), files = json::array();
  std::vector<Organ> organs;
  auto add_organ = [&](const std::string& name, const std::vector<Vec3>& seeds, bool bone, int label) {
    ido::logger().info("segmenting the {} from {} seed(s)", name, seeds.size());
    const segment::BalloonOptions& bo = bone ? bone_options : vessel_options;
    organs.push_back(segment_organ(name, ct, seeds, bo, dir, progress.get()));
    json entry;
    entry["options"] = {{"organ", bone ? "vertebra" : o.vessel_organ},
                        {"edge_reach_voxels", bo.edge_reach_voxels},
                        {"outside_level", bo.outside_level ? json(*bo.outside_level) : json(nullptr)},
                        {"roi_mm", roi ? json::array({{roi->min.x(), roi->min.y(), roi->min.z()},
                                                      {roi->max.x(), roi->max.y(), roi->max.z()}})
                                       : json(nullptr)}};
    entry["balloon"] = io::to_json(organs.back().balloon.report);
    entry["surface_checks"] = io::to_json(geometry::check_mesh(organs.back().balloon.surface));
    if (truth) {
      const auto t = label_mask(*truth, label);
      if (std::count(t.data().begin(), t.data().end(), std::uint8_t{1}) > 0)
        entry["scores"] = io::to_json(segment::compare_masks(organs.back().mask, t));
    }
    report["segmentation"][name] = entry;
    files.push_back(name + "_surface.stl");
    files.push_back(name + "_mask.nii.gz");
  };
  if (!vessel_seeds.empty()) add_organ("vessel", vessel_seeds, false, o.vessel_label);
  if (!bone_seeds.empty()) add_organ("bone", bone_seeds, true, o.bone_label);

  std::vector<const Organ*> organ_ptrs;
  for (const auto& organ : organs) organ_ptrs.push_back(&organ);
  organ_pictures(ct, organ_ptrs, vessel_seeds.empty() ? bone_seeds.front() : vessel_seeds.front(), dir,
                 pictures);

  // The drillable organ: the bone if one was segmented, else the vessel.
  const Organ& target = organs.back();
  const auto tets = mesh_organ(target, o.edge_mm, progress.get());
  io::write_tet_mesh(dir / (target.name + "_tets.vtu"), tets);
  files.push_back(target.name + "_tets.vtu");
  report["tetmesh"] = {{"organ", target.name}, {"quality", io::to_json(geometry::check_tet_mesh(tets))}};
  {
    viz::Renderer pic(900, 700);
    viz::TetClipOptions clip_options;
    clip_options.uniform_colour = Vec3(0.85, 0.8, 0.65);
    clip_options.edges = true;
    pic.add_tet_mesh_clipped(tets, {.point = geometry::Aabb::of(tets.vertices).centre(), .normal = Vec3(1, 0, 0)}, "", clip_options);
    pic.set_camera(pic.fit_camera(90, 10));
    pic.write_png(dir / "tetmesh_clip.png");
    pictures.push_back(json{{"file", "tetmesh_clip.png"}, {"what", "tetrahedral mesh, cut in half"}});
  }

  if (!o.drill_path.empty()) {
    report["drill"] = run_drill(o, tets, ct, dir, pictures);
    files.push_back("drilled.vtu");
    files.push_back("drilled_surface.stl");
  }
  if (!o.scene.empty()) {
    report["simulation"] = run_user_scene(o.scene, dir, progress.get());
    files.push_back("simulation/");
  }
  if (o.deform) {
    const auto vessel = std::find_if(organs.begin(), organs.end(), [](const Organ& x) { return x.name == "vessel"; });
    if (vessel == organs.end()) throw InvalidInput("--deform needs a vessel (--seed)");
    const auto vessel_tets = vessel->name == target.name ? tets : mesh_organ(*vessel, o.edge_mm, progress.get());
    report["deformation"] =
        run_deformation(vessel_tets, dir, static_cast<int>(o.deform_steps), pictures, progress.get());
    files.push_back("deformation/");
  }
  report["wall_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  files.push_back("report.json");
  files.push_back("summary.md");
  report["pictures"] = std::move(pictures);
  report["files"] = std::move(files);
  write_text_file((dir / "report.json").string(), report.dump(2) + "\n");
  write_text_file((dir / "summary.md").string(), summary_markdown(report));
  if (!g.quiet) std::printf("pipeline finished in %.1f s; summary: %s\n", report["wall_time_s"].get<double>(),
                            (dir / "summary.md").string().c_str());
}

void setup(CLI::App& app, const GlobalOptions& g) {
  auto* sub = app.add_subcommand(
      "pipeline", "CT → balloon segmentation → tetrahedral mesh → drilling and/or deformation, with pictures");
  auto opts = std::make_shared<Options>();
  sub->add_option("CT", opts->ct, "CT volume (NIfTI, NRRD, MetaImage, or a DICOM folder)")->required();
  sub->add_option("--seed", opts->seeds, "Vessel seed X,Y,Z (world mm, LPS); repeatable");
  sub->add_option("--seed-voxel", opts->seed_voxels, "Vessel seed I,J,K (voxel index); repeatable");
  sub->add_option("--bone-seed", opts->bone_seeds, "Bone seed X,Y,Z (world mm); repeatable");
  sub->add_option("--bone-seed-voxel", opts->bone_seed_voxels, "Bone seed I,J,K (voxel index); repeatable");
  sub->add_option("-o,--output", opts->out_dir, "Output folder (created if missing)")->required();
  sub->add_option("--drill-path", opts->drill_path, "Drill trajectory CSV (t,x,y,z) through the meshed organ");
  sub->add_option("--tool", opts->tool, "Burr: sphere:radius=MM[,shaft=MM] (default sphere:radius=2)");
  sub->add_option("--max-depth", opts->max_depth, "Finest drilling refinement level (default 3)")->check(CLI::Range(0, 8));
  sub->add_option("--edge", opts->edge_mm, "Tetrahedral lattice spacing (mm); 0 = from the voxel size")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--simulate", opts->scene, "Also run this simulation scene (JSON)");
  sub->add_flag("--deform", opts->deform, "Deform the segmented vessel (corotational FEM under gravity)");
  sub->add_option("--deform-steps", opts->deform_steps, "Steps of the deformation (default 60)")
      ->check(CLI::Range(1, 100000));
  sub->add_option("--vessel-reference", opts->vessel_reference,
                  "Vessel grey level (e.g. HU), with --vessel-tolerance; estimated at the seeds if omitted");
  sub->add_option("--vessel-tolerance", opts->vessel_tolerance, "Accepted departure from --vessel-reference");
  sub->add_option("--vessel-organ", opts->vessel_organ,
                  "the vessel's organ choice: generic (default), artery or vein (ido segment --organ); the bone "
                  "balloon always takes the vertebra choice");
  sub->add_option("--vessel-edge-reach", opts->vessel_edge_reach,
                  "As `ido segment --edge-reach` for the vessel: voxels the final snap may move the surface; 0 = no "
                  "limit (default)");
  sub->add_option("--vessel-outside-level", opts->vessel_outside_level,
                  "As `ido segment --outside-level` for the vessel: level of the tissue bounding it (e.g. 40 HU for "
                  "the lumen against its wall)");
  sub->add_option("--roi", opts->roi, "Region of interest x0,y0,z0,x1,y1,z1 (world mm) for both balloons, a safeguard");
  sub->add_option("--truth", opts->truth, "Label volume to score the segmentations against");
  sub->add_option("--vessel-label", opts->vessel_label, "Vessel's label in --truth (default 1)");
  sub->add_option("--bone-label", opts->bone_label, "Bone's label in --truth (default 2)");
  sub->callback([opts, &g] { run(*opts, g); });
}

const bool kRegistered = register_command({"pipeline", 60, setup});

}  // namespace
}  // namespace ido::cli
