// SPDX-License-Identifier: Apache-2.0
#include "cli_util.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fcntl.h>
#include <unistd.h>

#include "ido/core/atomic_file.h"
#include "ido/core/error.h"

namespace ido::cli {
namespace {
std::vector<std::string> split_commas(std::string_view text) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const auto pos = text.find(',', start);
    parts.emplace_back(text.substr(start, pos == std::string_view::npos ? text.npos : pos - start));
    if (pos == std::string_view::npos) break;
    start = pos + 1;
  }
  return parts;
}
}  // namespace

Vec3 parse_vec3(std::string_view text, std::string_view what) {
  const auto parts = split_commas(text);
  if (parts.size() != 3)
    throw InvalidInput(fmt::format("{}: expected three comma-separated numbers, got '{}'", what, text));
  Vec3 v;
  for (int a = 0; a < 3; ++a) {
    try {
      std::size_t used = 0;
      v[a] = std::stod(parts[a], &used);
      if (used != parts[a].size()) throw std::invalid_argument("trailing");
    } catch (const std::exception&) {
      throw InvalidInput(fmt::format("{}: '{}' is not a number", what, parts[a]));
    }
    if (!std::isfinite(v[a])) throw InvalidInput(fmt::format("{}: '{}' is not finite", what, parts[a]));
  }
  return v;
}

Index3 parse_index3(std::string_view text, std::string_view what) {
  const auto parts = split_commas(text);
  if (parts.size() != 3)
    throw InvalidInput(fmt::format("{}: expected three comma-separated integers, got '{}'", what, text));
  Index3 idx{};
  for (int a = 0; a < 3; ++a) {
    const auto& p = parts[a];
    const auto res = std::from_chars(p.data(), p.data() + p.size(), idx[a]);
    if (res.ec != std::errc{} || res.ptr != p.data() + p.size())
      throw InvalidInput(fmt::format("{}: '{}' is not an integer", what, p));
  }
  return idx;
}

std::unique_ptr<Progress> make_progress(bool quiet) {
  if (quiet || !::isatty(STDERR_FILENO)) return std::make_unique<Progress>();
  return std::make_unique<Progress>([last = -1](double fraction, std::string_view stage) mutable {
    const int percent = static_cast<int>(std::lround(std::clamp(fraction, 0.0, 1.0) * 100.0));
    if (percent == last) return;
    last = percent;
    const int filled = percent * 30 / 100;
    std::fprintf(stderr, "\r%-24.24s [%s%s] %3d%%", std::string(stage).c_str(),
                 std::string(static_cast<std::size_t>(filled), '#').c_str(),
                 std::string(static_cast<std::size_t>(30 - filled), ' ').c_str(), percent);
    if (percent >= 100) std::fputc('\n', stderr);
    std::fflush(stderr);
  });
}

void write_text_file(const std::string& path, const std::string& text) {
  write_file_atomically(path, [&](std::ostream& out) { out << text; }, false);
}

void check_output_file(const std::string& path, std::string_view option) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path p(path);
  if (path.empty() || fs::is_directory(p, ec) || !p.has_filename())
    throw InvalidInput(fmt::format("{} {}: is a folder, expected a file", option, path));
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    throw InvalidInput(fmt::format("{} {}: folder '{}' does not exist", option, path, dir.string()));
  const fs::path probe = dir / fmt::format(".tmp-{}-probe", static_cast<long>(::getpid()));
  const int guard = register_temporary_file(probe);
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0600);
  if (fd < 0) unregister_temporary_file(guard);
  if (fd < 0) throw InvalidInput(fmt::format("{} {}: cannot create a file in folder '{}'", option, path, dir.string()));
  ::close(fd);
  fs::remove(probe, ec);
  unregister_temporary_file(guard);
}

std::string OutputBatch::stage(const std::string& path, std::string_view option) {
  check_output_file(path, option);
  if (!m_batch.staged(path).empty())
    throw InvalidInput(fmt::format("{} {}: the same file is named by another output", option, path));
  return m_batch.stage(path).string();
}

void OutputBatch::commit() { m_batch.commit(); }

geometry::Aabb parse_roi(const std::string& text) {
  std::vector<double> v;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    const std::string part = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    try {
      std::size_t used = 0;
      v.push_back(std::stod(part, &used));
      if (used != part.size()) throw std::invalid_argument("trailing");
    } catch (const std::exception&) {
      throw InvalidInput(fmt::format("--roi: '{}' is not a number (expected x0,y0,z0,x1,y1,z1 in mm)", part));
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (v.size() != 6) throw InvalidInput(fmt::format("--roi: expected 6 numbers x0,y0,z0,x1,y1,z1 (mm), got {}", v.size()));
  const Vec3 a(v[0], v[1], v[2]), b(v[3], v[4], v[5]);
  if ((a.array() >= b.array()).any()) throw InvalidInput("--roi: each minimum must be below its maximum");
  return {a, b};
}

segment::Organ parse_organ_option(const std::string& name, std::string_view option) {
  try {
    return segment::parse_organ(name);
  } catch (const InvalidInput& e) {
    throw InvalidInput(fmt::format("{}: {}", option, e.what()));
  }
}

segment::BalloonOptions balloon_options_from_flags(std::string_view prefix, const segment::BalloonChoices& choices) {
  if (choices.reference.has_value() != choices.tolerance.has_value())
    throw InvalidInput(fmt::format("give {0}reference and {0}tolerance together (or neither, to estimate both at the seeds)",
                                   prefix));
  // The flag of each field: its name with hyphens, but --edge-reach for edge_reach_voxels.
  return segment::balloon_options(choices, [prefix](std::string_view field) {
    std::string flag(field == "edge_reach_voxels" ? std::string_view("edge_reach") : field);
    std::replace(flag.begin(), flag.end(), '_', '-');
    return std::string(prefix) + flag;
  });
}

}  // namespace ido::cli
