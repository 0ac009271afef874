// SPDX-License-Identifier: Apache-2.0
#include "ido/io/volume_io.h"

#include <cmath>
#include <cstring>
#include <fstream>

#include "dicom_writer.h"
#include "ido/core/error.h"
#include "io_test_util.h"
#include "support/test_support.h"

namespace ido::io {
namespace {
namespace fs = std::filesystem;

/// A small volume with distinct voxels, anisotropic spacing, an oblique direction and an
/// origin away from zero, so that any axis swap or lost field shows.
template <class T>
image::Volume<T> sample_volume() {
  const Mat3 dir = Eigen::AngleAxisd(0.3, Vec3(0.2, 1.0, 0.5).normalized()).toRotationMatrix();
  image::Volume<T> v(Index3{5, 4, 3}, Vec3(0.5, 0.75, 2.0), Vec3(-10.0, 20.5, 3.25), dir);
  for (std::size_t n = 0; n < v.voxel_count(); ++n)
    v.data()[n] = static_cast<T>(std::is_floating_point_v<T> ? 0.25 * double(n) - 3.5 : double(n * 3 % 50));
  return v;
}

template <class T>
void expect_same(const image::Volume<T>& a, const image::Volume<float>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(test::near(a.spacing()[i], b.spacing()[i], 1e-6));
    EXPECT_TRUE(test::near(a.origin()[i], b.origin()[i], 1e-5));
    for (int j = 0; j < 3; ++j) EXPECT_TRUE(test::near(a.direction()(i, j), b.direction()(i, j), 1e-6));
  }
  for (std::size_t n = 0; n < a.voxel_count(); ++n) ASSERT_EQ(static_cast<float>(a.data()[n]), b.data()[n]) << n;
}

template <class T>
void round_trip_all(const char* type_name) {
  const auto dir = test::scratch_dir(std::string("volume-rt-") + type_name);
  const auto v = sample_volume<T>();
  for (const char* name : {"v.nii", "v.nii.gz", "v.nrrd", "v.mha"}) {
    SCOPED_TRACE(name);
    write_volume(dir / name, v);
    VolumeFileInfo info;
    const auto back = read_volume(dir / name, &info);
    expect_same(v, back);
    EXPECT_EQ(info.components, 1);
  }
  // Only the final files remain: no temporaries left behind.
  int files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 4);
}

TEST(VolumeIo, RoundTripFloat) { round_trip_all<float>("float"); }
TEST(VolumeIo, RoundTripUint8) { round_trip_all<std::uint8_t>("uint8"); }
TEST(VolumeIo, RoundTripInt16) { round_trip_all<std::int16_t>("int16"); }

TEST(VolumeIo, PixelTypeIsReported) {
  const auto dir = test::scratch_dir("volume-pixeltype");
  write_volume(dir / "m.nii.gz", sample_volume<std::uint8_t>());
  write_volume(dir / "s.mha", sample_volume<std::int16_t>());
  VolumeFileInfo info;
  (void)read_volume(dir / "m.nii.gz", &info);
  EXPECT_EQ(info.format, "NIfTI");
  EXPECT_EQ(info.pixel_type, "unsigned_char");
  (void)read_volume(dir / "s.mha", &info);
  EXPECT_EQ(info.format, "MetaImage");
  EXPECT_EQ(info.pixel_type, "short");
}

// VTK's readers (not ours) see the same grid and voxels. VTK's image readers ignore the
// direction, so size, spacing and values are compared (and origin where VTK keeps it).
TEST(VolumeIo, VtkReadsWhatWeWrite) {
  const auto dir = test::scratch_dir("volume-vtk");
  auto v = sample_volume<float>();
  v.set_direction(Mat3::Identity());
  // vtkNrrdReader of VTK 9.1 misreads the "space directions" line ITK writes (it drops the
  // first axis), so NRRD is checked against the format text itself in NrrdHeaderAndPayload.
  for (auto [name, kind] : {std::pair{"v.nii", "nii"}, {"v.mha", "mha"}}) {
    SCOPED_TRACE(name);
    write_volume(dir / name, v);
    IDO_VTK_READ(j, kind, dir / name);
    ASSERT_EQ(j["dims"], (std::vector<int>{5, 4, 3}));
    for (int a = 0; a < 3; ++a) EXPECT_TRUE(test::near(j["spacing"][a].get<double>(), v.spacing()[a], 1e-6));
    if (std::string(kind) != "nii") {  // vtkNIFTIImageReader puts the origin in its qform matrix
      for (int a = 0; a < 3; ++a) EXPECT_TRUE(test::near(j["origin"][a].get<double>(), v.origin()[a], 1e-5));
    }
    const auto vals = j["values"].get<std::vector<double>>();
    ASSERT_EQ(vals.size(), v.voxel_count());
    for (std::size_t n = 0; n < vals.size(); ++n) ASSERT_EQ(vals[n], v.data()[n]) << n;
  }
}

// NRRD checked by hand against the specification (teem.sourceforge.net/nrrd/format.html):
// header fields, then raw little-endian float32 voxels, x fastest.
TEST(VolumeIo, NrrdHeaderAndPayload) {
  const auto dir = test::scratch_dir("volume-nrrd");
  auto v = sample_volume<float>();
  v.set_direction(Mat3::Identity());
  write_volume(dir / "v.nrrd", v);
  std::ifstream in(dir / "v.nrrd", std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  const auto end = text.find("\n\n");
  ASSERT_NE(end, std::string::npos);
  const std::string header = text.substr(0, end);
  EXPECT_EQ(header.rfind("NRRD", 0), 0u);
  EXPECT_NE(header.find("type: float"), std::string::npos) << header;
  EXPECT_NE(header.find("sizes: 5 4 3"), std::string::npos) << header;
  EXPECT_NE(header.find("space directions: (0.5,0,0) (0,0.75,0) (0,0,2)"), std::string::npos) << header;
  EXPECT_NE(header.find("space origin: (-10,20.5,3.25)"), std::string::npos) << header;
  EXPECT_NE(header.find("encoding: raw"), std::string::npos) << header;
  const std::string payload = text.substr(end + 2);
  ASSERT_EQ(payload.size(), v.voxel_count() * sizeof(float));
  for (std::size_t n = 0; n < v.voxel_count(); ++n) {
    float f;
    std::memcpy(&f, payload.data() + n * sizeof(float), sizeof f);
    ASSERT_EQ(f, v.data()[n]) << n;
  }
}

TEST(VolumeIo, FailedWriteKeepsOldFile) {
  const auto dir = test::scratch_dir("volume-atomic");
  const auto v = sample_volume<float>();
  write_volume(dir / "v.nii.gz", v);
  const auto before = fs::file_size(dir / "v.nii.gz");
  EXPECT_THROW(write_volume(dir / "v.nii.gz", image::Volume<float>{}), InvalidInput);
  EXPECT_EQ(fs::file_size(dir / "v.nii.gz"), before);
  EXPECT_THROW(write_volume(dir / "v.hdr5", v), IoError);
  EXPECT_THROW(write_volume(dir / "v.mhd", v), IoError);
  EXPECT_THROW(write_volume(dir / "missing-folder" / "v.nii", v), IoError);
}

TEST(VolumeIo, BadInputNamesThePath) {
  const auto dir = test::scratch_dir("volume-bad");
  auto expect_io = [](const fs::path& p, const std::string& fragment) {
    try {
      (void)read_volume(p);
      ADD_FAILURE() << "no exception for " << p;
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  expect_io(dir / "absent.nii", "no such file");
  std::ofstream(dir / "garbage.nii") << "this is not a NIfTI header";
  expect_io(dir / "garbage.nii", "NIfTI");
  std::ofstream(dir / "x.txt") << "1 2 3";
  expect_io(dir / "x.txt", "unknown volume extension");
  fs::create_directories(dir / "empty");
  expect_io(dir / "empty", "no DICOM series");
}

TEST(VolumeIo, DicomFolderWithTwoSeriesIsRejectedListingBoth) {
  const auto dir = test::scratch_dir("volume-mixed-dicom");
  test::write_tiny_dicom_series(dir, "1.2.826.0.1.3680043.2.1125.1.111", "a", 3);
  test::write_tiny_dicom_series(dir, "1.2.826.0.1.3680043.2.1125.1.222", "b", 2);
  try {
    (void)read_volume(dir);
    FAIL() << "mixed series accepted";
  } catch (const IoError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("2 DICOM series"), std::string::npos) << m;
    EXPECT_NE(m.find("1.2.826.0.1.3680043.2.1125.1.111"), std::string::npos) << m;
    EXPECT_NE(m.find("1.2.826.0.1.3680043.2.1125.1.222"), std::string::npos) << m;
  }
  // One series alone reads, slices stacked in order with their 2 mm spacing.
  const auto one = test::scratch_dir("volume-one-dicom");
  test::write_tiny_dicom_series(one, "1.2.826.0.1.3680043.2.1125.1.333", "c", 3);
  VolumeFileInfo info;
  const auto v = read_volume(one, &info);
  EXPECT_EQ(v.size(), (Index3{4, 3, 3}));
  EXPECT_TRUE(test::near(v.spacing()[2], 2.0, 1e-6));
  EXPECT_TRUE(test::near(v.spacing()[0], 0.5, 1e-6));
  EXPECT_EQ(info.series_uid, "1.2.826.0.1.3680043.2.1125.1.333");
  EXPECT_EQ(v(0, 0, 0), 100.0f);
  EXPECT_EQ(v(3, 2, 2), 102.0f);
}

// ido decodes a series' slices in parallel (one GDCMImageIO per slice); ITK's own series
// reader decodes them one after another. The voxels must be the same floats, the grid the
// same size.
void expect_same_as_itk_series_reader(const fs::path& dir) {
  const auto ours = read_volume(dir);
  const auto itk = test::read_series_with_itk(dir);
  ASSERT_EQ(ours.size(), (Index3{std::int64_t(itk.nx), std::int64_t(itk.ny), std::int64_t(itk.nz)}));
  ASSERT_EQ(ours.data().size(), itk.voxels.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < itk.voxels.size(); ++i)
    if (std::memcmp(&ours.data()[i], &itk.voxels[i], sizeof(float)) != 0) ++differ;
  EXPECT_EQ(differ, 0u) << "of " << itk.voxels.size() << " voxels in " << dir;
}

TEST(VolumeIo, DicomSlicesReadInParallelEqualItksSeriesReader) {
  const auto dir = test::scratch_dir("volume-parallel-dicom");
  test::write_tiny_dicom_series(dir, "1.2.826.0.1.3680043.2.1125.1.444", "p", 9);
  expect_same_as_itk_series_reader(dir);
  // Slice s holds 100 + s everywhere: a slice decoded into the wrong place shows.
  const auto v = read_volume(dir);
  for (std::int64_t k = 0; k < 9; ++k) EXPECT_EQ(v(1, 2, k), float(100 + k)) << "slice " << k;
}

TEST(VolumeIoData, AbdomenDicomSlicesEqualItksSeriesReader) {
  IDO_REQUIRE_SHARED_DATA();
  expect_same_as_itk_series_reader(*test::shared_data_dir() / "abdomen-dicom/series");
}

TEST(VolumeIoData, AbdomenDicomSeriesReads) {
  IDO_REQUIRE_SHARED_DATA();
  VolumeFileInfo info;
  const auto ct = read_volume(*test::shared_data_dir() / "abdomen-dicom/series", &info);
  EXPECT_EQ(info.format, "DICOM");
  EXPECT_EQ(ct.size(), (Index3{512, 512, 20}));
  EXPECT_TRUE(test::near(ct.spacing()[0], 0.977, 5e-4));
  EXPECT_TRUE(test::near(ct.spacing()[1], 0.977, 5e-4));
  EXPECT_TRUE(test::near(ct.spacing()[2], 2.0, 1e-6));
  // HU rescale applied: air outside the body is near -1000 HU, not a raw stored value.
  const auto [lo, hi] = std::minmax_element(ct.data().begin(), ct.data().end());
  EXPECT_LE(*lo, -1000.0f);
  EXPECT_GT(*hi, 500.0f);
}

// DICOM → NIfTI, then compare in physical space with the reference aorta mask, whose grid
// runs opposite to the DICOM one along j: every mask voxel's world position is mapped into
// the converted CT and sampled. README: mean ≈ 177 HU. Tolerance ±5 HU: trilinear sampling
// at voxel centres of a co-registered grid is exact, so the only slack is the README's
// rounding and the mask's own partial-volume boundary voxels.
TEST(VolumeIoData, AortaMeanHuAfterNiftiConversion) {
  IDO_REQUIRE_SHARED_DATA();
  const auto data = *test::shared_data_dir() / "abdomen-dicom";
  const auto dir = test::scratch_dir("volume-aorta");
  write_volume(dir / "ct.nii.gz", read_volume(data / "series"));
  const auto ct = read_volume(dir / "ct.nii.gz");
  const auto mask = read_volume(data / "aorta.nii.gz");
  double sum = 0.0;
  std::size_t count = 0;
  for (std::int64_t k = 0; k < mask.size(2); ++k)
    for (std::int64_t j = 0; j < mask.size(1); ++j)
      for (std::int64_t i = 0; i < mask.size(0); ++i)
        if (mask(i, j, k) > 0.5f) {
          const Vec3 w = mask.index_to_world(Vec3(double(i), double(j), double(k)));
          sum += ct.sample(w);
          ++count;
        }
  EXPECT_EQ(count, 11723u);
  const double mean = sum / double(count);
  EXPECT_TRUE(test::near(mean, 177.0, 5.0)) << mean;
  RecordProperty("aorta_mean_hu", std::to_string(mean));
}

}  // namespace
}  // namespace ido::io
