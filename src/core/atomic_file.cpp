// SPDX-License-Identifier: Apache-2.0
#include "ido/core/atomic_file.h"

#include <atomic>
#include <system_error>

#include <fmt/format.h>
#include <unistd.h>

#include "ido/core/error.h"

namespace ido {
namespace fs = std::filesystem;

namespace {
fs::path temp_sibling(const fs::path& path) {
  static std::atomic<unsigned> counter{0};
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  // Keep the full file name as the suffix so extension-driven writers (ITK) still work.
  return dir / fmt::format(".tmp-{}-{}-{}", static_cast<long>(::getpid()), counter++,
                           path.filename().string());
}

void check_target(const fs::path& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw IoError(path.string(), "is a folder, expected a file");
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    throw IoError(path.string(), fmt::format("folder '{}' does not exist", dir.string()));
}

void commit(const fs::path& tmp, const fs::path& path) {
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw IoError(path.string(), "cannot rename temporary file into place");
  }
}
}  // namespace

void write_file_atomically(const fs::path& path,
                           const std::function<void(std::ostream&)>& write_body, bool binary) {
  check_target(path);
  const fs::path tmp = temp_sibling(path);
  try {
    {
      std::ofstream out(tmp, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
      if (!out) throw IoError(path.string(), "cannot open for writing");
      write_body(out);
      out.flush();
      if (!out) throw IoError(path.string(), "write failed (disk full or I/O error?)");
    }
    commit(tmp, path);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

void write_path_atomically(const fs::path& path,
                           const std::function<void(const fs::path&)>& write_to) {
  check_target(path);
  const fs::path tmp = temp_sibling(path);
  try {
    write_to(tmp);
    std::error_code ec;
    if (!fs::exists(tmp, ec)) throw IoError(path.string(), "writer produced no file");
    commit(tmp, path);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

}  // namespace ido
