// SPDX-License-Identifier: Apache-2.0
// ParaView collections: write → read gives back the entries exactly (times to the last bit,
// names with XML's special characters); bad entries are refused before anything is written;
// malformed files are IoErrors naming the file.
#include "ido/io/pvd.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "support/test_support.h"

namespace ido::io {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(Pvd, WriteThenReadGivesTheEntriesBack) {
  const fs::path dir = test::scratch_dir("pvd_round_trip");
  std::vector<PvdEntry> entries;
  for (int i = 0; i < 25; ++i) entries.push_back({0.1 * i + 1e-17 * i, "frames/frame_" + std::to_string(i) + ".vtu"});
  entries.push_back({1.0 / 3.0, "surface & \"quoted\" <name>'s.vtp"});
  entries.push_back({-2.5e-300, "tiny.vtu"});
  write_pvd(dir / "run.pvd", entries);
  const std::vector<PvdEntry> back = read_pvd(dir / "run.pvd");
  ASSERT_EQ(back.size(), entries.size());
  for (std::size_t i = 0; i < entries.size(); ++i) {
    EXPECT_EQ(back[i].time_s, entries[i].time_s) << i;  // %.17g: exact
    EXPECT_EQ(back[i].file, entries[i].file) << i;
  }
  // It is a VTK collection ParaView opens.
  const std::string text = slurp(dir / "run.pvd");
  EXPECT_NE(text.find("<VTKFile type=\"Collection\""), std::string::npos);
  EXPECT_NE(text.find("&amp;"), std::string::npos) << "special characters are escaped";
  // An empty series is a valid collection too.
  write_pvd(dir / "empty.pvd", {});
  EXPECT_TRUE(read_pvd(dir / "empty.pvd").empty());
}

TEST(Pvd, BadEntriesAreRefusedAndNothingIsWritten) {
  const fs::path dir = test::scratch_dir("pvd_bad_entries");
  for (const PvdEntry& bad : {PvdEntry{std::nan(""), "a.vtu"}, PvdEntry{std::numeric_limits<double>::infinity(), "a.vtu"},
                              PvdEntry{1.0, ""}}) {
    try {
      write_pvd(dir / "bad.pvd", {{0.0, "ok.vtu"}, bad});
      FAIL() << "accepted";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("bad.pvd"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir / "bad.pvd"));
  }
  // An existing file is left as it was.
  write_pvd(dir / "kept.pvd", {{0.5, "x.vtu"}});
  EXPECT_THROW(write_pvd(dir / "kept.pvd", {{std::nan(""), "y.vtu"}}), InvalidInput);
  ASSERT_EQ(read_pvd(dir / "kept.pvd").size(), 1U);
  EXPECT_EQ(read_pvd(dir / "kept.pvd")[0].file, "x.vtu");
}

TEST(Pvd, MalformedFilesAreIoErrorsNamingTheFileAndLine) {
  const fs::path dir = test::scratch_dir("pvd_malformed");
  struct Case {
    const char* name;
    const char* text;
    const char* says;
  };
  const Case cases[] = {
      {"root.pvd", "<?xml version=\"1.0\"?>\n<Other type=\"Collection\"><Collection/></Other>\n", "<Other>"},
      {"type.pvd", "<VTKFile type=\"UnstructuredGrid\"><Collection/></VTKFile>\n", "Collection"},
      {"nocoll.pvd", "<VTKFile type=\"Collection\">\n</VTKFile>\n", "no <Collection>"},
      {"nofile.pvd", "<VTKFile type=\"Collection\">\n<Collection>\n<DataSet timestep=\"1\"/>\n</Collection>\n</VTKFile>\n",
       "without a file"},
      {"time.pvd",
       "<VTKFile type=\"Collection\">\n<Collection>\n<DataSet timestep=\"0\" file=\"a.vtu\"/>\n"
       "<DataSet timestep=\"soon\" file=\"b.vtu\"/>\n</Collection>\n</VTKFile>\n",
       "'soon'"},
      {"inf.pvd", "<VTKFile type=\"Collection\">\n<Collection>\n<DataSet timestep=\"inf\" file=\"b.vtu\"/>\n</Collection>\n</VTKFile>\n",
       "'inf'"},
  };
  for (const Case& c : cases) {
    std::ofstream(dir / c.name) << c.text;
    try {
      (void)read_pvd(dir / c.name);
      FAIL() << c.name << " accepted";
    } catch (const IoError& e) {
      EXPECT_EQ(e.path(), (dir / c.name).string());
      EXPECT_NE(e.problem().find(c.says), std::string::npos) << c.name << ": " << e.what();
    }
  }
  // The bad timestep is on line 4 of time.pvd.
  try {
    (void)read_pvd(dir / "time.pvd");
  } catch (const IoError& e) {
    EXPECT_EQ(e.location().line, 4);
  }
  // A missing timestep reads as time 0; a missing file is an IoError.
  std::ofstream(dir / "notime.pvd") << "<VTKFile type=\"Collection\"><Collection><DataSet file=\"a.vtu\"/></Collection></VTKFile>";
  const auto e = read_pvd(dir / "notime.pvd");
  ASSERT_EQ(e.size(), 1U);
  EXPECT_EQ(e[0].time_s, 0.0);
  EXPECT_THROW((void)read_pvd(dir / "absent.pvd"), IoError);
}

}  // namespace
}  // namespace ido::io
