// SPDX-License-Identifier: Apache-2.0
#include "snapshots.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <system_error>
#include <utility>

#include <fmt/format.h>

#include "ido/core/error.h"
#include "ido/io/memory_budget.h"

namespace ido::cli {

std::array<int, 2> parse_picture_size(const std::string& text, std::string_view what) {
  const auto x = text.find('x');
  int w = 0, h = 0;
  try {
    std::size_t used = 0;
    if (x == std::string::npos) throw InvalidInput("");
    w = std::stoi(text.substr(0, x), &used);
    if (used != x) throw InvalidInput("");
    const std::string rest = text.substr(x + 1);
    h = std::stoi(rest, &used);
    if (used != rest.size()) throw InvalidInput("");
  } catch (const std::exception&) {
    throw InvalidInput(fmt::format("{} must be WIDTHxHEIGHT in pixels, e.g. 800x600, got '{}'", what, text));
  }
  if (w < 1 || h < 1 || w > 16384 || h > 16384)
    throw InvalidInput(fmt::format("{} must be within 1..16384 pixels per side, got '{}'", what, text));
  // The picture's colour and depth buffers and its PNG: about 12 bytes a pixel.
  const std::uint64_t bytes = io::saturating_product({std::uint64_t(w), std::uint64_t(h), 12});
  if (bytes > io::memory_limit_bytes())
    throw InvalidInput(fmt::format("{} {}: a picture of {} x {} pixels needs {}, over the memory limit of {} "
                                   "(ido --memory-limit)",
                                   what, text, w, h, io::format_bytes(bytes), io::format_bytes(io::memory_limit_bytes())));
  return {w, h};
}

namespace {

bool is_snapshot_name(const std::string& name) {
  // snapshot_NNNN.png, exactly four digits
  if (name.size() != 17 || name.rfind("snapshot_", 0) != 0 || name.substr(13) != ".png") return false;
  return std::all_of(name.begin() + 9, name.begin() + 13, [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
}

}  // namespace

SnapshotWriter::SnapshotWriter(std::filesystem::path dir, const SnapshotOptions& options, std::string_view argument)
    : m_dir(std::move(dir)), m_options(options) {
  namespace fs = std::filesystem;
  if (m_dir.empty()) throw InvalidInput(fmt::format("{}: the folder name is empty", argument));
  if (options.width_px < 1 || options.height_px < 1 || options.width_px > 16384 || options.height_px > 16384)
    throw InvalidInput(fmt::format("{}: picture size {}x{} is outside 1..16384 pixels per side", argument,
                                   options.width_px, options.height_px));
  std::error_code ec;
  const auto status = fs::status(m_dir, ec);
  if (fs::exists(status) && !fs::is_directory(status))
    throw InvalidInput(fmt::format("{} {}: exists and is not a folder", argument, m_dir.string()));
  if (!fs::exists(status)) {
    fs::create_directories(m_dir, ec);
    if (ec || !fs::is_directory(m_dir))
      throw InvalidInput(fmt::format("{} {}: cannot create the folder ({})", argument, m_dir.string(),
                                     ec ? ec.message() : "not a folder"));
  }
  if (::access(m_dir.c_str(), W_OK | X_OK) != 0)
    throw InvalidInput(fmt::format("{} {}: the folder is not writable ({})", argument, m_dir.string(),
                                   std::strerror(errno)));
  std::vector<fs::path> stale;
  for (const auto& entry : fs::directory_iterator(m_dir, ec))
    if (entry.is_regular_file() && is_snapshot_name(entry.path().filename().string())) stale.push_back(entry.path());
  for (const auto& p : stale) fs::remove(p, ec);
}

void SnapshotWriter::frame(const Vec3& lo, const Vec3& hi) {
  m_camera = viz::Camera::orbit(lo, hi, m_options.azimuth_deg, m_options.elevation_deg, m_options.projection,
                                double(m_options.width_px) / double(m_options.height_px));
}

std::filesystem::path SnapshotWriter::write(viz::Renderer& renderer) {
  if (renderer.width() != m_options.width_px || renderer.height() != m_options.height_px)
    throw InvalidInput(fmt::format("snapshots: renderer is {}x{} px, pictures are {}x{} px", renderer.width(),
                                   renderer.height(), m_options.width_px, m_options.height_px));
  if (!m_camera) {
    const auto b = renderer.bounds();
    frame(b.min, b.max);
  }
  renderer.set_camera(*m_camera);
  return write(renderer.render());
}

std::filesystem::path SnapshotWriter::write(const viz::Image& image) {
  const auto path = m_dir / fmt::format("snapshot_{:04d}.png", m_files.size());
  viz::write_png(path, image);
  m_files.push_back(path);
  return path;
}

nlohmann::json SnapshotWriter::files_json() const {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& f : m_files) out.push_back(f.string());
  return out;
}

viz::Image side_by_side(const viz::Image& left, const viz::Image& right) {
  viz::Image out;
  out.width = left.width + right.width;
  out.height = std::max(left.height, right.height);
  out.rgba.assign(std::size_t(out.width) * std::size_t(out.height) * 4, 255);
  auto blit = [&](const viz::Image& im, int x0) {
    for (int y = 0; y < im.height; ++y)
      std::copy_n(im.pixel(0, y), std::size_t(im.width) * 4,
                  out.rgba.data() + 4 * (std::size_t(y) * std::size_t(out.width) + std::size_t(x0)));
  };
  blit(left, 0);
  blit(right, left.width);
  return out;
}

}  // namespace ido::cli
