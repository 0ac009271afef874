// SPDX-License-Identifier: Apache-2.0
// Inputs that once got through (issue 30) — volumes that hold fewer bytes than their header
// promises, non-finite voxels, spacings of 0/-1/NaN, devices named like mesh files, scene
// files that are not JSON — run through the built tool: exit 2, one stderr line naming the
// file, nothing written, and a small peak memory (measured per run with wait4). A hang fails
// through `timeout` (exit 124) and the test's ctest TIMEOUT; no wall-clock time is asserted.
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <tuple>

#include <nlohmann/json.hpp>

#include "../io/dicom_writer.h"
#include "ido/io/volume_io.h"
#include "support/test_support.h"

namespace ido::cli {
namespace {
namespace fs = std::filesystem;

struct Measured {
  int exit_code = -1;
  std::string out, err;
  long max_rss_kib = 0;  ///< peak resident memory of the tool (and `timeout`)
};

#if defined(__SANITIZE_ADDRESS__)
// AddressSanitizer's shadow memory and quarantine add about 40 MiB to any run of the tool (a
// refused input peaks at 137-142 MiB there); a declared allocation would still be gigabytes.
constexpr long kMemoryCeilingKib = 200 * 1024;
#else
constexpr long kMemoryCeilingKib = 100 * 1024;  // 100 MiB
#endif

/// Runs `ido ARGS` under `timeout 60` and measures its peak memory through wait4. Its
/// stdout/stderr go to a folder of their own so that @p args' folders stay as they were.
Measured run_measured(const std::string& args) {
  static int counter = 0;
  const fs::path logs = test::scratch_dir("bad-input-cli-logs-" + std::to_string(counter++));
  const std::string cmd = "exec timeout 60 " + test::tool_path().string() + " " + args + " >" +
                          (logs / "out").string() + " 2>" + (logs / "err").string() + " </dev/null";
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  Measured m;
  int status = 0;
  rusage usage{};
  if (pid > 0 && wait4(pid, &status, 0, &usage) == pid) {
    m.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    m.max_rss_kib = usage.ru_maxrss;
  }
  auto slurp = [](const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  m.out = slurp(logs / "out");
  m.err = slurp(logs / "err");
  return m;
}

std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

std::set<std::string> names_in(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

/// The shape every refusal here must have: exit 2, one line naming @p file and holding
/// @p fragment, no library internals, nothing on stdout, under the memory ceiling.
void expect_refused(const Measured& r, const fs::path& file, const std::string& fragment) {
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find(file.string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(fragment), std::string::npos) << "expected '" << fragment << "' in: " << r.err;
  for (const char* internal : {"0x", "json.exception", "nifti_", "[nrrd]", "ITK ERROR", "internal error"})
    EXPECT_EQ(r.err.find(internal), std::string::npos) << internal << " in: " << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_LT(r.max_rss_kib, kMemoryCeilingKib);
}

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
void write_bytes(const fs::path& p, std::string_view bytes) {
  std::ofstream(p, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}
void write_gzip(const fs::path& p, std::string_view bytes) {
  gzFile f = gzopen(p.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  ASSERT_EQ(gzwrite(f, bytes.data(), static_cast<unsigned>(bytes.size())), static_cast<int>(bytes.size()));
  gzclose(f);
}

/// An uncompressed NIfTI-1 scan of int16 noise (so that it does not compress to nothing):
/// 48 × 40 × 24 voxels, 352 header bytes then 92 160 voxel bytes.
std::string noisy_scan_nii(const fs::path& dir) {
  image::Volume<std::int16_t> v(Index3{48, 40, 24}, Vec3(0.7, 0.7, 2.5), Vec3(0, 0, 0));
  std::mt19937 rng(30);
  std::uniform_int_distribution<int> hu(-1000, 1500);
  for (auto& x : v.data()) x = static_cast<std::int16_t>(hu(rng));
  v.data().back() = 7;  // a last voxel that is not 0
  io::write_volume(dir / "scan.nii", v);
  auto bytes = read_bytes(dir / "scan.nii");
  fs::remove(dir / "scan.nii");
  return bytes;
}

void set_float(std::string& header, std::size_t offset, float value) {
  std::memcpy(header.data() + offset, &value, sizeof value);
}

// The first 200 bytes of a real .nii.gz, and its first half: the gzip stream ends early.
// `ido info` and `ido convert` refuse it and convert writes nothing.
TEST(CliBadVolume, GzipStreamCutShortIsRefused) {
  const auto dir = test::scratch_dir("bad-cli-cut-gzip");
  const std::string nii = noisy_scan_nii(dir);
  write_gzip(dir / "scan.nii.gz", nii);
  const std::string gz = read_bytes(dir / "scan.nii.gz");
  ASSERT_GT(gz.size(), 2000u);
  write_bytes(dir / "first200.nii.gz", gz.substr(0, 200));
  write_bytes(dir / "half.nii.gz", gz.substr(0, gz.size() / 2));
  // ITK reads a gzip stream only from a .nii.gz: a misnamed file is told so.
  write_bytes(dir / "gzip_named.nii", gz);
  // The whole file reads (the checks refuse only what is wrong).
  ASSERT_EQ(run_measured("info " + q(dir / "scan.nii.gz")).exit_code, 0);
  expect_refused(run_measured("info " + q(dir / "gzip_named.nii")), dir / "gzip_named.nii",
                 "is gzip-compressed but not named .nii.gz");
  const auto before = names_in(dir);
  expect_refused(run_measured("info " + q(dir / "first200.nii.gz")), dir / "first200.nii.gz", "cut short");
  expect_refused(run_measured("info " + q(dir / "half.nii.gz")), dir / "half.nii.gz", "gzip stream is cut short");
  expect_refused(run_measured("convert " + q(dir / "half.nii.gz") + " " + q(dir / "out.nii")), dir / "half.nii.gz",
                 "gzip stream is cut short");
  EXPECT_EQ(names_in(dir), before);
}

// An intact gzip stream (and a plain .nii) that hold fewer voxel bytes than the header says,
// and a vox_offset past the end of the data.
TEST(CliBadVolume, FewerVoxelBytesThanDeclaredIsRefused) {
  const auto dir = test::scratch_dir("bad-cli-short-voxels");
  const std::string nii = noisy_scan_nii(dir);
  write_gzip(dir / "short.nii.gz", nii.substr(0, nii.size() - 1000));
  write_bytes(dir / "short.nii", nii.substr(0, nii.size() - 1000));
  std::string far = nii;
  set_float(far, 108, 1.0e6f);  // vox_offset
  write_gzip(dir / "offset.nii.gz", far);
  write_bytes(dir / "offset.nii", far);
  const auto before = names_in(dir);
  const std::string declared = "too few for the 92160 bytes of voxels";
  expect_refused(run_measured("info " + q(dir / "short.nii.gz")), dir / "short.nii.gz", declared);
  expect_refused(run_measured("info " + q(dir / "short.nii")), dir / "short.nii", declared);
  expect_refused(run_measured("info " + q(dir / "offset.nii.gz")), dir / "offset.nii.gz", "from byte 1000000");
  expect_refused(run_measured("convert " + q(dir / "offset.nii") + " " + q(dir / "o.mha")), dir / "offset.nii",
                 "from byte 1000000");
  EXPECT_EQ(names_in(dir), before);
}

// Non-finite voxels are refused in every format (one check for all readers).
TEST(CliBadVolume, NonFiniteVoxelsAreRefused) {
  const auto dir = test::scratch_dir("bad-cli-nan");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  image::Volume<float> all_nan(Index3{6, 5, 4}, Vec3(1, 1, 1), Vec3(0, 0, 0), Mat3::Identity(), nan);
  io::write_volume(dir / "nan.nii.gz", all_nan);
  image::Volume<float> one_inf(Index3{6, 5, 4}, Vec3(1, 1, 1), Vec3(0, 0, 0), Mat3::Identity(), 1.0f);
  one_inf(2, 3, 1) = std::numeric_limits<float>::infinity();
  io::write_volume(dir / "inf.nrrd", one_inf);
  // NIfTI's reader (niftilib) turns a NaN into 0: one among ones must still be found.
  image::Volume<float> one_nan(Index3{6, 5, 4}, Vec3(1, 1, 1), Vec3(0, 0, 0), Mat3::Identity(), 1.0f);
  one_nan(5, 4, 3) = nan;
  io::write_volume(dir / "one_nan.nii.gz", one_nan);
  io::write_volume(dir / "one_nan.nii", one_nan);
  const auto before = names_in(dir);
  for (const char* name : {"one_nan.nii.gz", "one_nan.nii"})
    expect_refused(run_measured("info " + q(dir / name)), dir / name,
                   "1 of 120 voxels are not finite (NaN or infinite), the first at voxel (5, 4, 3)");
  expect_refused(run_measured("info " + q(dir / "nan.nii.gz")), dir / "nan.nii.gz", "120 of 120 voxels are not finite");
  expect_refused(run_measured("convert " + q(dir / "inf.nrrd") + " " + q(dir / "o.nii")), dir / "inf.nrrd",
                 "1 of 120 voxels are not finite (NaN or infinite), the first at voxel (2, 3, 1)");
  EXPECT_EQ(names_in(dir), before);
}

// pixdim 0, -1 and NaN: refused with the message a MetaImage with spacing 0 gets.
TEST(CliBadVolume, NonPositiveOrNanSpacingIsRefusedAlikeInNiftiAndMetaImage) {
  const auto dir = test::scratch_dir("bad-cli-pixdim");
  const std::string nii = noisy_scan_nii(dir);
  for (const float p : {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN()}) {
    std::string bad = nii;
    set_float(bad, 80, p);  // pixdim[1]
    const fs::path file = dir / "pixdim.nii.gz";
    write_gzip(file, bad);
    expect_refused(run_measured("info " + q(file)), file, "mm is not positive and finite");
    fs::remove(file);
  }
  const fs::path mha = dir / "spacing0.mha";
  write_bytes(mha, "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\nElementSpacing = 0 1 1\n"
                   "ElementType = MET_UCHAR\nElementDataFile = LOCAL\n" + std::string(8, '\1'));
  expect_refused(run_measured("info " + q(mha)), mha, "spacing 0 × 1 × 1 mm is not positive and finite");
}

// Devices and pipes named like mesh or volume files: refused at once, nothing read.
TEST(CliBadInput, DevicesAndPipesAreRefusedWithoutReading) {
  const auto dir = test::scratch_dir("bad-cli-devices");
  fs::create_symlink("/dev/zero", dir / "x.stl");
  fs::create_symlink("/dev/urandom", dir / "x.ply");
  fs::create_symlink("/dev/zero", dir / "x.nii.gz");
  fs::create_symlink("/dev/zero", dir / "x.vtu");
  ASSERT_EQ(mkfifo((dir / "x.obj").c_str(), 0600), 0);
  for (const char* name : {"x.stl", "x.ply", "x.nii.gz", "x.vtu", "x.obj"}) {
    SCOPED_TRACE(name);
    expect_refused(run_measured("info " + q(dir / name)), dir / name, "is not a regular file");
  }
  expect_refused(run_measured("convert " + q(dir / "x.stl") + " " + q(dir / "y.ply")), dir / "x.stl",
                 "is not a regular file");
  EXPECT_FALSE(fs::exists(dir / "y.ply"));
}

// A header that declares more voxels than memory holds is refused before anything is
// allocated, with the need and the limit.
TEST(CliBadVolume, DeclaredSizeOverTheMemoryLimitIsRefusedBeforeAllocating) {
  const auto dir = test::scratch_dir("bad-cli-huge");
  std::string nii = noisy_scan_nii(dir);
  const std::int16_t huge = 32767;
  for (std::size_t axis = 0; axis < 3; ++axis) std::memcpy(nii.data() + 42 + 2 * axis, &huge, 2);
  write_gzip(dir / "huge.nii.gz", nii);
  const auto r = run_measured("info " + q(dir / "huge.nii.gz"));
  expect_refused(r, dir / "huge.nii.gz", "32767×32767×32767 voxels need 128 TiB, over the memory limit of");
}

// Scene files: a JSON syntax error gives the line and column in ido's words; a folder is
// named as such; no output folder is made.
TEST(CliBadInput, SceneErrorsAreOneLineAndMakeNoOutput) {
  const auto dir = test::scratch_dir("bad-cli-scene");
  write_bytes(dir / "scene.json", "{\n  \"dt_s\": 0.001,\n    }\n");
  const auto r = run_measured("simulate " + q(dir / "scene.json") + " -o " + q(dir / "out"));
  expect_refused(r, "scene.json:3: column 5:", "syntax error while parsing object key");
  fs::create_directory(dir / "folder.json");
  const auto f = run_measured("simulate " + q(dir / "folder.json") + " -o " + q(dir / "out"));
  expect_refused(f, dir / "folder.json", "is a folder, not a scene file");
  EXPECT_FALSE(fs::exists(dir / "out"));
  // A number beyond double's range (found by fuzz_scene): it was nlohmann's out_of_range
  // escaping as "internal error: [json.exception.out_of_range.406] ...", exit 1.
  write_bytes(dir / "overflow.json", "{\n  \"dt_s\": 1e4000,\n  \"steps\": 10\n}\n");
  expect_refused(run_measured("simulate " + q(dir / "overflow.json") + " -o " + q(dir / "out")),
                 dir / "overflow.json", "overflow.json:2: not valid JSON: number overflow parsing '1e4000'");
  EXPECT_FALSE(fs::exists(dir / "out"));
}

}  // namespace
}  // namespace ido::cli

namespace ido::cli {
namespace {

// --memory-limit sets the budget every declared size is checked against; a bad value is
// refused naming the option.
TEST(CliBadInput, MemoryLimitOptionBoundsWhatAFileMayDeclare) {
  const auto dir = test::scratch_dir("bad-cli-memory-limit");
  image::Volume<float> v(Index3{16, 16, 16}, Vec3(1, 1, 1), Vec3(0, 0, 0), Mat3::Identity(), 1.0f);
  io::write_volume(dir / "v.nii.gz", v);  // 16 KiB of float voxels
  EXPECT_EQ(run_measured("--memory-limit 1M info " + q(dir / "v.nii.gz")).exit_code, 0);
  expect_refused(run_measured("--memory-limit 8K info " + q(dir / "v.nii.gz")), dir / "v.nii.gz",
                 "16×16×16 voxels need 16 KiB, over the memory limit of 8 KiB");
  const auto bad = run_measured("--memory-limit lots info " + q(dir / "v.nii.gz"));
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
  EXPECT_NE(bad.err.find("--memory-limit: 'lots' is not a memory size"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace ido::cli

namespace ido::cli {
namespace {

// A DICOM series with a slice whose pixel data element is missing (GDCM's series scan left
// that file out, so the series read with a slice less) or cut short (GDCM read the missing
// pixels as 0 and only warned): exit 2 naming the slice's file, and `ido convert` writes
// nothing.
TEST(CliBadVolume, DicomSliceWithoutAllItsPixelDataIsRefused) {
  const auto dir = test::scratch_dir("bad-cli-dicom");
  for (const std::string how : {"missing", "short"}) {
    SCOPED_TRACE(how);
    const auto series = dir / how;
    fs::create_directories(series);
    test::write_tiny_dicom_series(series, "1.2.826.0.1.3680043.2.1125.30." + std::to_string(how.size()), "s", 4);
    ASSERT_EQ(run_measured("info " + q(series)).exit_code, 0);
    const auto slice = series / "s1.dcm";
    const std::string bytes = read_bytes(slice);
    const auto pixel_tag = bytes.rfind(std::string("\xe0\x7f\x10\x00", 4));  // (7FE0,0010), little endian
    ASSERT_NE(pixel_tag, std::string::npos);
    // 4 x 3 int16 pixels: 24 bytes after the element's header; "short" keeps 18 of them.
    write_bytes(slice, how == "missing" ? bytes.substr(0, pixel_tag) : bytes.substr(0, bytes.size() - 6));
    const std::string expected = how == "missing" ? "DICOM slice has no pixel data"
                                                  : "DICOM pixel data is cut short: 18 of its 24 bytes are in the file";
    expect_refused(run_measured("info " + q(series)), slice, expected);
    expect_refused(run_measured("convert " + q(series) + " " + q(dir / (how + ".nii.gz"))), slice, expected);
    EXPECT_FALSE(fs::exists(dir / (how + ".nii.gz")));
  }
}

// A header/data pair whose data file holds fewer bytes than the header declares, or is
// missing: MetaImage (.mhd + .raw, .mhd + .zraw) and NRRD (.nhdr + .raw, .nhdr + .raw.gz).
TEST(CliBadVolume, DetachedDataFileShorterThanItsHeaderIsRefused) {
  const auto dir = test::scratch_dir("bad-cli-detached");
  const std::string mhd = "ObjectType = Image\nNDims = 3\nDimSize = 4 4 4\nElementSpacing = 1 1 1\n"
                          "ElementType = MET_FLOAT\n";
  const std::string nhdr = "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4 4\nspacings: 1 1 1\nendian: little\n";
  const std::string whole(256, '\0'), part(100, '\0');
  write_bytes(dir / "whole.raw", whole);
  write_bytes(dir / "part.raw", part);
  write_bytes(dir / "ok.mhd", mhd + "ElementDataFile = whole.raw\n");
  write_bytes(dir / "ok.nhdr", nhdr + "encoding: raw\ndata file: whole.raw\n");
  for (const char* ok : {"ok.mhd", "ok.nhdr"}) ASSERT_EQ(run_measured("info " + q(dir / ok)).exit_code, 0) << ok;
  write_bytes(dir / "short.mhd", mhd + "ElementDataFile = part.raw\n");
  write_bytes(dir / "short.nhdr", nhdr + "encoding: raw\ndata file: part.raw\n");
  write_bytes(dir / "skip.nhdr", nhdr + "encoding: raw\nbyte skip: 200\ndata file: whole.raw\n");
  write_bytes(dir / "gone.mhd", mhd + "ElementDataFile = gone.raw\n");
  write_bytes(dir / "gone.nhdr", nhdr + "encoding: raw\ndata file: gone.raw\n");
  // A gzip stream of 100 of the 256 bytes.
  write_gzip(dir / "part.raw.gz", part);
  write_bytes(dir / "short_gz.nhdr", nhdr + "encoding: gzip\ndata file: part.raw.gz\n");
  // MetaImage's compressed data file is a zlib stream: cut one short.
  {
    std::vector<unsigned char> z(compressBound(256));
    uLongf n = static_cast<uLongf>(z.size());
    ASSERT_EQ(compress(z.data(), &n, reinterpret_cast<const Bytef*>(whole.data()), 256), Z_OK);
    write_bytes(dir / "cut.zraw", std::string(reinterpret_cast<const char*>(z.data()), n / 2));
  }
  write_bytes(dir / "short_z.mhd", mhd + "CompressedData = True\nElementDataFile = cut.zraw\n");
  const auto before = names_in(dir);
  const std::string too_few = "has 100 bytes, too few for the 256 bytes of voxels the header declares";
  expect_refused(run_measured("info " + q(dir / "short.mhd")), dir / "short.mhd", "data file '" + (dir / "part.raw").string() + "' " + too_few);
  expect_refused(run_measured("info " + q(dir / "short.nhdr")), dir / "short.nhdr", "data file '" + (dir / "part.raw").string() + "' " + too_few);
  expect_refused(run_measured("info " + q(dir / "skip.nhdr")), dir / "skip.nhdr", "has 256 bytes, too few for the 256 bytes of voxels the header declares after 200 skipped");
  expect_refused(run_measured("convert " + q(dir / "gone.mhd") + " " + q(dir / "out.nii")), dir / "gone.mhd", "gone.raw' does not exist");
  expect_refused(run_measured("info " + q(dir / "gone.nhdr")), dir / "gone.nhdr", "gone.raw' does not exist");
  expect_refused(run_measured("convert " + q(dir / "short_gz.nhdr") + " " + q(dir / "out.nii")), dir / "short_gz.nhdr",
                 "part.raw.gz' ends after 100 of the 256 bytes of voxels the header declares");
  expect_refused(run_measured("info " + q(dir / "short_z.mhd")), dir / "short_z.mhd", "cut.zraw' ");
  EXPECT_EQ(names_in(dir), before);
}

}  // namespace
}  // namespace ido::cli

namespace ido::cli {
namespace {

// A size an option declares is checked against the memory budget before anything is
// allocated: a phantom's grid (--spacing; it was std::bad_alloc, exit 1) and a picture's
// pixels (--size). The refusal names the option; nothing is written.
TEST(CliBadInput, OptionDeclaredSizesAreCheckedAgainstTheMemoryLimit) {
  const auto dir = test::scratch_dir("bad-cli-option-sizes");
  const auto ct = dir / "ct.nii.gz";
  expect_refused(run_measured("phantom sphere --spacing 0.001,0.001,0.001 -o " + q(ct) + " --labels " +
                              q(dir / "labels.nii.gz")),
                 "--spacing 0.001,0.001,0.001", "the sphere phantom's grid of at least 47000 x 47000 x 47000 voxels needs 472 TiB");
  // Under a small limit: 0.5 mm (96 x 96 x 96 voxels, 4.4 MiB; counted from the smallest
  // extent the 2-mm probe allows) is refused, 1 mm (48 x 48 x 48, 553 KiB) is made.
  expect_refused(run_measured("--memory-limit 1M phantom sphere --spacing 0.5,0.5,0.5 -o " + q(ct)),
                 "--spacing 0.5,0.5,0.5", "94 x 94 x 94 voxels needs 3.96 MiB, over the memory limit of 1 MiB");
  EXPECT_TRUE(names_in(dir).empty());
  EXPECT_EQ(run_measured("--memory-limit 1M phantom sphere -o " + q(ct)).exit_code, 0);
  expect_refused(run_measured("--memory-limit 64M render " + q(ct) + " -o " + q(dir / "p.png") + " --size 16384x16384"),
                 "--size 16384x16384", "a picture of 16384 x 16384 pixels needs 3 GiB, over the memory limit of 64 MiB");
  EXPECT_EQ(names_in(dir), std::set<std::string>{"ct.nii.gz"});
}

// ido tetmesh --edge: the lattice it declares is checked against the memory budget before it
// is allocated, and a spacing the mesher refuses is named as the option (--edge), not as the
// library's edge_mm. On the 47-mm sphere mask under a 16 MiB limit, 0.25 mm (at least 1.3e7
// lattice vertices, 114 MiB) is refused and 2 mm (2.1e4) is meshed.
TEST(CliBadInput, TetmeshEdgeIsNamedAndCheckedAgainstTheMemoryLimit) {
  const auto dir = test::scratch_dir("bad-cli-tetmesh-edge");
  const auto labels = dir / "labels.nii.gz";
  ASSERT_EQ(run_measured("phantom sphere -o " + q(dir / "ct.nii.gz") + " --labels " + q(labels)).exit_code, 0);
  const auto out = dir / "mesh.vtu";
  const auto tetmesh = [&](const std::string& global, const std::string& edge) {
    return run_measured(global + "tetmesh " + q(labels) + " -o " + q(out) + " --edge " + edge);
  };
  for (const auto& [global, edge, fragment] :
       {std::tuple<std::string, std::string, std::string>{"", "0.001", "needs 1.66 PiB, over the memory limit"},
        {"--memory-limit 16M ", "0.25", "needs 114 MiB, over the memory limit of 16 MiB"},
        {"", "0.05", "the lattice spacing is too small"}}) {
    SCOPED_TRACE(edge);
    const auto r = tetmesh(global, edge);
    expect_refused(r, "--edge " + edge, fragment);
    EXPECT_EQ(r.err.find("edge_mm"), std::string::npos) << r.err;
  }
  EXPECT_EQ(names_in(dir), (std::set<std::string>{"ct.nii.gz", "labels.nii.gz"}));
  EXPECT_EQ(tetmesh("--memory-limit 16M ", "2").exit_code, 0);
  EXPECT_TRUE(fs::exists(out));
}

}  // namespace
}  // namespace ido::cli
