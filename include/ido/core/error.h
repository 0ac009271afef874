// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

namespace ido {

/// Base of every exception ido throws at its API boundary.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

/// The caller passed something the library cannot work with: a bad argument, a malformed
/// value, a mesh or volume that breaks a documented precondition.
class InvalidInput : public Error {
 public:
  explicit InvalidInput(const std::string& what) : Error(what) {}
};

/// Where in a file a problem was found: a 1-based line for text formats, a byte offset
/// for binary ones.
struct FileLocation {
  std::optional<std::int64_t> line;         ///< 1-based line number
  std::optional<std::int64_t> byte_offset;  ///< 0-based byte offset
};

/// A file could not be read or written, or its content is malformed. The message always
/// starts with the path, then the location if known, then the problem:
/// `mesh.ply:12: expected 3 vertex indices, found 2`.
class IoError : public Error {
 public:
  IoError(const std::string& path, const std::string& problem, FileLocation where = {});
  [[nodiscard]] const std::string& path() const noexcept { return m_path; }
  [[nodiscard]] const FileLocation& location() const noexcept { return m_where; }
  [[nodiscard]] const std::string& problem() const noexcept { return m_problem; }

 private:
  std::string m_path;
  std::string m_problem;
  FileLocation m_where;
};

/// A long operation was cancelled through its Progress object.
class Cancelled : public Error {
 public:
  Cancelled() : Error("operation cancelled") {}
};

}  // namespace ido
