// SPDX-License-Identifier: Apache-2.0
#include "text_parser.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <system_error>

#include <fmt/format.h>

#include "ido/io/memory_budget.h"
#include "parsers.h"

namespace ido::io::detail {

namespace {
bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }
}  // namespace

void TextCursor::skip_blanks(bool cross_lines) {
  while (m_pos < m_text.size()) {
    const char c = m_text[m_pos];
    if (is_blank(c)) {
      ++m_pos;
    } else if (c == '\n' && cross_lines) {
      ++m_pos;
      ++m_line;
    } else if (m_comment != '\0' && c == m_comment) {
      while (m_pos < m_text.size() && m_text[m_pos] != '\n') ++m_pos;
      if (!cross_lines) return;
    } else {
      return;
    }
  }
}

std::string_view TextCursor::next() {
  skip_blanks(true);
  const std::size_t start = m_pos;
  while (m_pos < m_text.size() && !is_blank(m_text[m_pos]) && m_text[m_pos] != '\n') ++m_pos;
  return m_text.substr(start, m_pos - start);
}

std::string_view TextCursor::expect(std::string_view what) {
  const auto t = next();
  if (t.empty()) fail(fmt::format("file ends where {} was expected", what));
  return t;
}

std::string_view TextCursor::next_on_line() {
  skip_blanks(false);
  if (m_pos >= m_text.size() || m_text[m_pos] == '\n' || (m_comment && m_text[m_pos] == m_comment)) return {};
  const std::size_t start = m_pos;
  while (m_pos < m_text.size() && !is_blank(m_text[m_pos]) && m_text[m_pos] != '\n') ++m_pos;
  return m_text.substr(start, m_pos - start);
}

void TextCursor::skip_line() {
  while (m_pos < m_text.size() && m_text[m_pos] != '\n') ++m_pos;
  if (m_pos < m_text.size()) {
    ++m_pos;
    ++m_line;
  }
}

std::string_view TextCursor::rest_of_line() {
  skip_blanks(false);
  const std::size_t start = m_pos;
  while (m_pos < m_text.size() && m_text[m_pos] != '\n') ++m_pos;
  std::string_view r = m_text.substr(start, m_pos - start);
  while (!r.empty() && is_blank(r.back())) r.remove_suffix(1);
  return r;
}

bool TextCursor::at_end() {
  skip_blanks(true);
  return m_pos >= m_text.size();
}

double TextCursor::read_double(std::string_view what) {
  const auto t = expect(what);
  double v = 0.0;
  if (!to_double(t, v)) fail(fmt::format("expected a number for {}, found '{}'", what, t.substr(0, 40)));
  return v;
}

std::int64_t TextCursor::read_int(std::string_view what) {
  const auto t = expect(what);
  std::int64_t v = 0;
  if (!to_int(t, v)) fail(fmt::format("expected an integer for {}, found '{}'", what, t.substr(0, 40)));
  return v;
}

void TextCursor::fail(const std::string& problem) const {
  throw IoError(m_name, problem, {.line = m_line, .byte_offset = std::nullopt});
}

bool to_double(std::string_view token, double& value) {
  if (token.empty()) return false;
  if (token.front() == '+') token.remove_prefix(1);
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  // Non-finite spellings ("nan", "inf") parse here; validation reports them with context.
  return ec == std::errc() && end == token.data() + token.size();
}

bool to_int(std::string_view token, std::int64_t& value) {
  if (token.empty()) return false;
  if (token.front() == '+') token.remove_prefix(1);
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && end == token.data() + token.size();
}

void invalid(const std::string& name, const std::string& problem, FileLocation where) {
  // Same layout as ido::IoError's message, so both read alike.
  const IoError shaped(name, problem, where);
  throw InvalidInput(shaped.what());
}

std::string lower_extension(const std::string& filename) {
  std::string ext = std::filesystem::path(filename).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

std::string read_file_bytes(const std::filesystem::path& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (!fs::exists(status)) throw IoError(path.string(), "no such file");
  if (fs::is_directory(status)) throw IoError(path.string(), "is a folder, expected a file");
  // A device or pipe (/dev/zero named x.stl) has no size and may never end.
  if (!fs::is_regular_file(status)) throw IoError(path.string(), "is not a regular file (a device, pipe or socket)");
  const auto size = fs::file_size(path, ec);
  if (ec) throw IoError(path.string(), "cannot read the file size: " + ec.message());
  if (size == 0) throw IoError(path.string(), "file is empty");
  check_memory_budget(path.string(), size, fmt::format("the file's {} bytes", size));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string(), "cannot open for reading");
  // Exactly the size found above: a file that grows meanwhile is read as it was.
  std::string bytes(static_cast<std::size_t>(size), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(size));
  if (in.bad()) throw IoError(path.string(), "read failed");
  bytes.resize(static_cast<std::size_t>(in.gcount()));
  if (bytes.empty()) throw IoError(path.string(), "file is empty");
  return bytes;
}

}  // namespace ido::io::detail
