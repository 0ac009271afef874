// SPDX-License-Identifier: Apache-2.0
// Private to ido::io: a minimal XML reader for the subset VTK's XML files and .pvd indexes
// use (elements, attributes, text, comments, the <?xml?> declaration; the five predefined
// entities). Written by hand because Debian's XML libraries (libxml2, expat, tinyxml2)
// would add a dependency for ~150 lines, and none of them reports the byte positions our
// error messages need or lets us step over VTK's raw appended binary block.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace ido::io::detail {

struct XmlNode {
  std::string name;
  std::map<std::string, std::string> attributes;
  std::vector<std::unique_ptr<XmlNode>> children;
  std::size_t text_begin = 0;  ///< byte range of the element's text before its first child
  std::size_t text_end = 0;
  std::size_t offset = 0;      ///< byte offset of the start tag

  [[nodiscard]] const XmlNode* child(std::string_view n) const;
  [[nodiscard]] std::vector<const XmlNode*> children_named(std::string_view n) const;
  [[nodiscard]] const std::string* attribute(std::string_view n) const;
};

/// Parses @p text into its root element. @throws IoError naming @p name and the line.
std::unique_ptr<XmlNode> parse_xml(std::string_view text, const std::string& name);

/// 1-based line of a byte offset.
std::int64_t line_at(std::string_view text, std::size_t offset);

/// Escapes &, <, >, " for an attribute value.
std::string xml_escape(std::string_view s);

}  // namespace ido::io::detail
