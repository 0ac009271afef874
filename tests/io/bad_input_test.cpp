// SPDX-License-Identifier: Apache-2.0
// Every file of the bad-input catalogue is rejected with the catalogued exception type and a
// message naming the file, the location and the problem.
#include "catalogue.h"
#include "ido/core/error.h"
#include "ido/io/file_info.h"
#include "ido/io/mesh_io.h"
#include "ido/io/volume_io.h"

namespace ido::io {
namespace {

void read_any(const std::filesystem::path& p) {
  switch (file_kind(p)) {
    case FileKind::Volume: (void)read_volume(p); break;
    case FileKind::TriangleMesh: (void)read_triangle_mesh(p); break;
    case FileKind::TetMesh: (void)read_tet_mesh(p); break;
  }
}

TEST(BadInput, CatalogueHasAtLeast25Entries) { EXPECT_GE(test::bad_catalogue().size(), 25u); }

TEST(BadInput, EveryFileIsRejectedWithItsMessage) {
  const auto dir = test::fixtures_dir() / "bad";
  for (const auto& bad : test::bad_catalogue()) {
    SCOPED_TRACE(bad.file);
    const std::string path = (dir / bad.file).string();
    std::string type, message;
    try {
      read_any(path);
    } catch (const IoError& e) {
      type = "IoError";
      message = e.what();
    } catch (const InvalidInput& e) {
      type = "InvalidInput";
      message = e.what();
    }
    EXPECT_EQ(type, bad.exception) << message;
    EXPECT_NE(message.find(test::location_text(path, bad.location)), std::string::npos)
        << "expected location '" << bad.location << "' in: " << message;
    EXPECT_NE(message.find(bad.fragment), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace ido::io
