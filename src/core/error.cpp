// SPDX-License-Identifier: Apache-2.0
#include "ido/core/error.h"

#include <fmt/format.h>

namespace ido {
namespace {
std::string format_io_message(const std::string& path, const std::string& problem,
                              const FileLocation& where) {
  if (where.line) return fmt::format("{}:{}: {}", path, *where.line, problem);
  if (where.byte_offset) return fmt::format("{}: byte {}: {}", path, *where.byte_offset, problem);
  return fmt::format("{}: {}", path, problem);
}
}  // namespace

IoError::IoError(const std::string& path, const std::string& problem, FileLocation where)
    : Error(format_io_message(path, problem, where)),
      m_path(path),
      m_problem(problem),
      m_where(where) {}

}  // namespace ido
