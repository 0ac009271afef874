// SPDX-License-Identifier: Apache-2.0
#include "xml_lite.h"

#include <algorithm>

#include <fmt/format.h>

#include "ido/core/error.h"

namespace ido::io::detail {

const XmlNode* XmlNode::child(std::string_view n) const {
  for (const auto& c : children)
    if (c->name == n) return c.get();
  return nullptr;
}

std::vector<const XmlNode*> XmlNode::children_named(std::string_view n) const {
  std::vector<const XmlNode*> out;
  for (const auto& c : children)
    if (c->name == n) out.push_back(c.get());
  return out;
}

const std::string* XmlNode::attribute(std::string_view n) const {
  const auto it = attributes.find(std::string(n));
  return it == attributes.end() ? nullptr : &it->second;
}

std::int64_t line_at(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  return 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(offset), '\n');
}

std::string xml_escape(std::string_view s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

namespace {

class Parser {
 public:
  Parser(std::string_view t, const std::string& n) : m_t(t), m_name(n) {}

  std::unique_ptr<XmlNode> document() {
    skip_misc();
    if (m_p >= m_t.size() || m_t[m_p] != '<') fail("expected an XML element");
    auto root = element(0);
    skip_misc();
    if (m_p < m_t.size()) fail("content after the root element");
    return root;
  }

 private:
  [[noreturn]] void fail(const std::string& problem) const {
    throw IoError(m_name, problem, {.line = line_at(m_t, m_p), .byte_offset = std::nullopt});
  }
  static bool space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
  void skip_space() {
    while (m_p < m_t.size() && space(m_t[m_p])) ++m_p;
  }
  bool starts(std::string_view s) const { return m_t.substr(m_p, s.size()) == s; }
  void skip_past(std::string_view end, const char* what) {
    const auto e = m_t.find(end, m_p);
    if (e == std::string_view::npos) fail(fmt::format("unterminated {}", what));
    m_p = e + end.size();
  }
  /// Declarations, comments and blanks between elements.
  void skip_misc() {
    while (true) {
      skip_space();
      if (starts("<?")) skip_past("?>", "XML declaration");
      else if (starts("<!--")) skip_past("-->", "comment");
      else if (starts("<!")) skip_past(">", "declaration");
      else return;
    }
  }
  std::string name_token() {
    const std::size_t s = m_p;
    while (m_p < m_t.size() && !space(m_t[m_p]) && m_t[m_p] != '>' && m_t[m_p] != '/' && m_t[m_p] != '=') ++m_p;
    if (s == m_p) fail("expected a name");
    return std::string(m_t.substr(s, m_p - s));
  }
  std::string unescape(std::string_view v) {
    std::string out;
    for (std::size_t i = 0; i < v.size(); ++i) {
      if (v[i] != '&') {
        out += v[i];
        continue;
      }
      const auto semi = v.find(';', i);
      if (semi == std::string_view::npos) fail("unterminated entity in attribute");
      const auto ent = v.substr(i + 1, semi - i - 1);
      if (ent == "lt") out += '<';
      else if (ent == "gt") out += '>';
      else if (ent == "amp") out += '&';
      else if (ent == "quot") out += '"';
      else if (ent == "apos") out += '\'';
      else fail(fmt::format("unknown entity '&{};'", ent.substr(0, 20)));
      i = semi;
    }
    return out;
  }

  std::unique_ptr<XmlNode> element(int depth) {
    if (depth > 64) fail("elements nested too deeply");
    auto node = std::make_unique<XmlNode>();
    node->offset = m_p;
    ++m_p;  // '<'
    node->name = name_token();
    while (true) {
      skip_space();
      if (m_p >= m_t.size()) fail(fmt::format("unterminated start tag <{}>", node->name));
      if (starts("/>")) {
        m_p += 2;
        node->text_begin = node->text_end = m_p;
        return node;
      }
      if (m_t[m_p] == '>') {
        ++m_p;
        break;
      }
      std::string key = name_token();
      skip_space();
      if (m_p >= m_t.size() || m_t[m_p] != '=') fail(fmt::format("attribute '{}' has no value", key));
      ++m_p;
      skip_space();
      if (m_p >= m_t.size() || (m_t[m_p] != '"' && m_t[m_p] != '\'')) fail("attribute value must be quoted");
      const char q = m_t[m_p++];
      const auto e = m_t.find(q, m_p);
      if (e == std::string_view::npos) fail("unterminated attribute value");
      node->attributes[key] = unescape(m_t.substr(m_p, e - m_p));
      m_p = e + 1;
    }
    node->text_begin = m_p;
    while (true) {
      const auto lt = m_t.find('<', m_p);
      if (lt == std::string_view::npos) fail(fmt::format("element <{}> is not closed (truncated?)", node->name));
      m_p = lt;
      if (starts("</")) {
        if (node->children.empty()) node->text_end = m_p;
        m_p += 2;
        const std::string closing = name_token();
        if (closing != node->name) fail(fmt::format("</{}> closes <{}>", closing, node->name));
        skip_space();
        if (m_p >= m_t.size() || m_t[m_p] != '>') fail("malformed end tag");
        ++m_p;
        return node;
      }
      if (starts("<!--")) {
        skip_past("-->", "comment");
        continue;
      }
      // The element's own text is what precedes its first child (VTK puts
      // <InformationKey> children after a DataArray's values).
      if (node->children.empty()) node->text_end = m_p;
      node->children.push_back(element(depth + 1));
    }
  }

  std::string_view m_t;
  const std::string& m_name;
  std::size_t m_p = 0;
};

}  // namespace

std::unique_ptr<XmlNode> parse_xml(std::string_view text, const std::string& name) {
  return Parser(text, name).document();
}

}  // namespace ido::io::detail
