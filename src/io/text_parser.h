// SPDX-License-Identifier: Apache-2.0
// Private to ido::io: a whitespace tokenizer over a text buffer that tracks the line, and
// a bounds-checked binary reader that tracks the byte offset. Both throw ido::IoError
// naming the file and the position. Hand-written: the formats need positions in errors,
// which iostreams do not give.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>

#include "ido/core/error.h"

namespace ido::io::detail {

/// Tokens of a text file, separated by blanks; lines are counted from 1.
class TextCursor {
 public:
  TextCursor(std::string_view text, std::string name) : m_text(text), m_name(std::move(name)) {}

  /// Next token on any line; empty at end of file. Skips '#'-comments when enabled.
  std::string_view next();
  /// Next token, which must exist (@p what names it in the error).
  std::string_view expect(std::string_view what);
  /// Next token, which must lie on the current line; empty if the line has ended.
  std::string_view next_on_line();
  /// Skips the rest of the current line.
  void skip_line();
  /// The rest of the current line (trimmed), consuming it.
  std::string_view rest_of_line();
  /// True at end of input (after skipping blanks and comments).
  bool at_end();

  double read_double(std::string_view what);
  std::int64_t read_int(std::string_view what);

  [[nodiscard]] std::int64_t line() const { return m_line; }
  [[nodiscard]] std::size_t offset() const { return m_pos; }
  [[nodiscard]] const std::string& name() const { return m_name; }
  void set_comment_char(char c) { m_comment = c; }

  [[noreturn]] void fail(const std::string& problem) const;

 private:
  void skip_blanks(bool cross_lines);
  std::string_view m_text;
  std::string m_name;
  std::size_t m_pos = 0;
  std::int64_t m_line = 1;
  char m_comment = '\0';
};

/// Parses a whole token as a number; false on junk, overflow or trailing characters.
bool to_double(std::string_view token, double& value);
bool to_int(std::string_view token, std::int64_t& value);

/// Reads fixed-size values from a byte buffer, little or big endian.
class ByteCursor {
 public:
  ByteCursor(std::string_view bytes, std::string name, std::size_t start = 0)
      : m_bytes(bytes), m_name(std::move(name)), m_pos(start) {}

  template <class T>
  T read(bool big_endian, std::string_view what) {
    static_assert(std::is_arithmetic_v<T>);
    if (m_bytes.size() - m_pos < sizeof(T) || m_pos > m_bytes.size())
      fail("file ends inside " + std::string(what));
    unsigned char raw[sizeof(T)];
    std::memcpy(raw, m_bytes.data() + m_pos, sizeof(T));
    if (big_endian != (std::endian::native == std::endian::big))
      for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(raw[i], raw[sizeof(T) - 1 - i]);
    T v;
    std::memcpy(&v, raw, sizeof(T));
    m_pos += sizeof(T);
    return v;
  }
  void skip(std::size_t n, std::string_view what) {
    if (m_bytes.size() - m_pos < n) fail("file ends inside " + std::string(what));
    m_pos += n;
  }
  [[nodiscard]] std::size_t offset() const { return m_pos; }
  [[nodiscard]] std::size_t remaining() const { return m_bytes.size() - m_pos; }
  [[noreturn]] void fail(const std::string& problem) const {
    throw IoError(m_name, problem, {.line = std::nullopt, .byte_offset = static_cast<std::int64_t>(m_pos)});
  }

 private:
  std::string_view m_bytes;
  std::string m_name;
  std::size_t m_pos;
};

/// InvalidInput with IoError's message layout ("file:line: problem" / "file: byte N: ...").
[[noreturn]] void invalid(const std::string& name, const std::string& problem, FileLocation where = {});

/// Lower-case extension with the dot, e.g. ".stl"; "" if none.
std::string lower_extension(const std::string& filename);

}  // namespace ido::io::detail
