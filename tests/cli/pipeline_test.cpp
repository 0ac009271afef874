// SPDX-License-Identifier: Apache-2.0
// `ido pipeline` end to end on the spine-aorta phantom: every stage's files are written and
// the stages agree with each other and with the phantom's ground truth.
#include <cmath>
#include <fstream>
#include <iterator>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ido/io/volume_io.h"
#include "ido/segment/phantom.h"
#include "support/test_support.h"

namespace ido {
namespace fs = std::filesystem;
namespace {

struct PipelineInput {
  fs::path dir, ct, labels, path;
  Vec3 vessel_seed, bone_seed;
};

PipelineInput make_input(const std::string& name) {
  PipelineInput in;
  in.dir = test::scratch_dir(name);
  segment::PhantomOptions po;
  po.noise_hu = 20.0;
  po.blur_voxels = 0.7;
  const auto ph = segment::make_phantom(segment::PhantomKind::SpineAorta, po);
  in.ct = in.dir / "ct.nii.gz";
  in.labels = in.dir / "labels.nii.gz";
  in.path = in.dir / "path.csv";
  io::write_volume(in.ct, ph.ct_hu);
  io::write_volume(in.labels, ph.labels);
  for (std::size_t s = 0; s < ph.seeds_mm.size(); ++s)
    (ph.seed_labels[s] == 1 ? in.vessel_seed : in.bone_seed) = ph.seeds_mm[s];
  std::ofstream csv(in.path);
  csv << "t,x,y,z\n";
  double t = 0.0;
  for (std::size_t i = 0; i < ph.drill_path_mm.size(); ++i) {
    if (i > 0) t += (ph.drill_path_mm[i] - ph.drill_path_mm[i - 1]).norm() / 8.0;
    csv << fmt::format("{},{},{},{}\n", t, ph.drill_path_mm[i].x(), ph.drill_path_mm[i].y(), ph.drill_path_mm[i].z());
  }
  return in;
}

std::string seed_arg(const Vec3& p) { return fmt::format("{},{},{}", p.x(), p.y(), p.z()); }

bool is_png(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  char magic[8] = {};
  in.read(magic, 8);
  return in && std::string(magic + 1, 3) == "PNG";
}

}  // namespace

TEST(PipelineCli, SpineAortaEndToEnd) {
  const auto in = make_input("pipeline-e2e");
  const fs::path out = in.dir / "out";
  // --vessel-edge-reach 2: the options reach the vessel's balloon (and the report), not the bone's.
  const auto r = test::run_tool(fmt::format(
      "pipeline {} --seed {} --bone-seed {} --truth {} --drill-path {} --max-depth 2 --deform --deform-steps 5 "
      "--vessel-edge-reach 2 -o {}",
      in.ct.string(), seed_arg(in.vessel_seed), seed_arg(in.bone_seed), in.labels.string(), in.path.string(),
      out.string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;

  std::ifstream rf(out / "report.json");
  const auto report = nlohmann::json::parse(rf);
  for (const auto& f : report["files"]) {
    const std::string name = f.get<std::string>();
    EXPECT_TRUE(fs::exists(out / name)) << name;
  }
  for (const auto& p : report["pictures"]) EXPECT_TRUE(is_png(out / p["file"].get<std::string>())) << p["file"];

  // Segmentation: both organs closed, without self-intersections; the vessel matches truth.
  for (const char* organ : {"vessel", "bone"}) {
    const auto& b = report["segmentation"][organ]["balloon"];
    EXPECT_TRUE(b["closed"].get<bool>()) << organ;
    EXPECT_EQ(b["self_intersections"].get<int>(), 0) << organ;
    EXPECT_TRUE(report["segmentation"][organ].contains("scores")) << organ;
  }
  EXPECT_GE(report["segmentation"]["vessel"]["scores"]["dice"].get<double>(), 0.97);
  EXPECT_EQ(report["segmentation"]["vessel"]["options"]["edge_reach_voxels"].get<double>(), 2.0);
  EXPECT_EQ(report["segmentation"]["bone"]["options"]["edge_reach_voxels"].get<double>(), 0.0);
  EXPECT_TRUE(report["segmentation"]["vessel"]["options"]["outside_level"].is_null());
  // The bone's balloon takes the vertebra choice (kept apart from neighbours; none here).
  EXPECT_EQ(report["segmentation"]["bone"]["options"]["organ"], "vertebra");
  EXPECT_EQ(report["segmentation"]["vessel"]["options"]["organ"], "generic");
  // The vertebra too, posterior arch included: the ring around the canal makes it genus 1.
  EXPECT_GE(report["segmentation"]["bone"]["scores"]["dice"].get<double>(), 0.97);
  EXPECT_EQ(report["segmentation"]["bone"]["balloon"]["euler_characteristic"].get<int>(), 0);

  // Tetrahedral mesh of the bone: valid and of the segmented volume (to the lattice's size).
  const auto& q = report["tetmesh"]["quality"];
  EXPECT_EQ(report["tetmesh"]["organ"], "bone");
  EXPECT_EQ(q["inverted"].get<int>(), 0);
  EXPECT_GE(q["min_dihedral_deg"].get<double>(), 10.7);
  EXPECT_TRUE(q["boundary_closed"].get<bool>());
  const double tet_volume = q["volume_mm3"].get<double>();
  EXPECT_TRUE(test::rel_near(tet_volume, report["segmentation"]["bone"]["balloon"]["volume_mm3"].get<double>(), 0.05));

  // Drilling: material is conserved — removed + remaining = the meshed volume.
  const auto& d = report["drill"];
  const double removed = d["removed_volume_mm3"].get<double>();
  EXPECT_GT(removed, 1.0);
  EXPECT_TRUE(test::rel_near(removed + d["remaining_volume_mm3"].get<double>(), tet_volume, 1e-6));
  EXPECT_LE(d["bytes_per_node"].get<double>(), 4.0);

  // Deformation: finite energies; the clamped vessel has stored elastic energy.
  const auto& e = report["deformation"]["final_energy"];
  EXPECT_TRUE(std::isfinite(e["total_mj"].get<double>()));
  EXPECT_GT(e["elastic_mj"].get<double>(), 0.0);
  // The deformation's world is built in memory; the scene file written beside it describes the
  // same world: `ido simulate` on it gives the same frames and energies, byte for byte.
  const fs::path rerun = out / "deformation_rerun";
  const auto s = test::run_tool(fmt::format("-q simulate {} -o {}", (out / "deformation" / "scene.json").string(),
                                            rerun.string()));
  ASSERT_EQ(s.exit_code, 0) << s.err;
  auto bytes = [](const fs::path& p) {
    std::ifstream file(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(file), {});
  };
  for (const char* file : {"energy.csv", "simulation.pvd", "frame_0000.vtu", "frame_0005.vtu"}) {
    EXPECT_FALSE(bytes(out / "deformation" / file).empty()) << file;
    EXPECT_EQ(bytes(out / "deformation" / file), bytes(rerun / file)) << file;
  }
}

TEST(PipelineCli, BadInputExitsTwoAndWritesNoReport) {
  const auto in = make_input("pipeline-bad");
  const fs::path out = in.dir / "out";
  auto r = test::run_tool(fmt::format("pipeline {} -o {}", in.ct.string(), out.string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--seed"), std::string::npos) << r.err;
  r = test::run_tool(fmt::format("pipeline {} --seed {} --drill-path {} -o {}", in.ct.string(),
                                 seed_arg(in.vessel_seed), (in.dir / "missing.csv").string(), out.string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("missing.csv"), std::string::npos) << r.err;
  r = test::run_tool(fmt::format("pipeline {} --seed-voxel 9999,0,0 -o {}", in.ct.string(), out.string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--seed-voxel"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "report.json"));
  // The vessel's balloon options are checked before anything is read or written.
  const fs::path none = in.dir / "not-made";
  for (const auto& [args, named] : {std::pair<std::string, std::string>{"--vessel-tolerance 50", "--vessel-reference"},
                                    {"--vessel-reference 300 --vessel-tolerance -5", "--vessel-tolerance"},
                                    {"--vessel-edge-reach -1", "--vessel-edge-reach"},
                                    {"--vessel-outside-level nan", "--vessel-outside-level"},
                                    {"--vessel-organ liver", "--vessel-organ"},
                                    {"--vessel-organ vertebra", "--vessel-organ"},
                                    {"--roi 0,0,0,10,10", "--roi"},
                                    {"--roi 0,0,0,-10,10,10", "--roi"}}) {
    r = test::run_tool(fmt::format("pipeline {} --seed {} {} -o {}", in.ct.string(), seed_arg(in.vessel_seed), args,
                                   none.string()));
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_NE(r.err.find(named), std::string::npos) << args << ": " << r.err;
    EXPECT_FALSE(fs::exists(none)) << args;
  }
}

}  // namespace ido
