// SPDX-License-Identifier: Apache-2.0
// ParaView collection files (.pvd): a VTKFile of type "Collection" listing DataSets with a
// timestep and a file.
#include "ido/io/pvd.h"

#include <fmt/format.h>

#include "ido/core/atomic_file.h"
#include "parsers.h"
#include "text_parser.h"
#include "xml_lite.h"

namespace ido::io {

namespace detail {
std::vector<PvdEntry> parse_pvd(std::string_view bytes, const std::string& name) {
  const auto root = parse_xml(bytes, name);
  auto fail = [&](const XmlNode& at, const std::string& problem) {
    throw IoError(name, problem, {.line = line_at(bytes, at.offset), .byte_offset = std::nullopt});
  };
  if (root->name != "VTKFile") fail(*root, fmt::format("root element is <{}>, expected <VTKFile>", root->name));
  const auto* type = root->attribute("type");
  if (!type || *type != "Collection") fail(*root, "VTKFile type must be 'Collection'");
  const XmlNode* coll = root->child("Collection");
  if (!coll) fail(*root, "no <Collection> element");
  std::vector<PvdEntry> out;
  for (const auto* ds : coll->children_named("DataSet")) {
    PvdEntry e;
    const auto* file = ds->attribute("file");
    if (!file || file->empty()) fail(*ds, "<DataSet> without a file");
    e.file = *file;
    if (const auto* t = ds->attribute("timestep")) {
      if (!to_double(*t, e.time_s) || !std::isfinite(e.time_s)) fail(*ds, fmt::format("timestep '{}' is not a number", *t));
    }
    out.push_back(std::move(e));
  }
  return out;
}
}  // namespace detail

void write_pvd(const std::filesystem::path& path, const std::vector<PvdEntry>& entries) {
  for (const auto& e : entries)
    if (!std::isfinite(e.time_s) || e.file.empty())
      throw InvalidInput(path.string() + ": every .pvd entry needs a finite time and a file name");
  write_file_atomically(
      path,
      [&](std::ostream& out) {
        out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
               "  <Collection>\n";
        for (const auto& e : entries)
          out << fmt::format("    <DataSet timestep=\"{:.17g}\" group=\"\" part=\"0\" file=\"{}\"/>\n", e.time_s,
                             detail::xml_escape(e.file));
        out << "  </Collection>\n</VTKFile>\n";
      },
      false);
}

std::vector<PvdEntry> read_pvd(const std::filesystem::path& path) {
  return detail::parse_pvd(detail::read_file_bytes(path), path.string());
}

}  // namespace ido::io
