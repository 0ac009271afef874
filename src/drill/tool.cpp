// SPDX-License-Identifier: Apache-2.0
#include "ido/drill/tool.h"

#include <charconv>
#include <cmath>
#include <string>

#include "ido/core/error.h"

namespace ido::drill {

std::vector<Vec3> fibonacci_sphere(int n) {
  std::vector<Vec3> p;
  p.reserve(static_cast<std::size_t>(n));
  const double golden = kPi * (3.0 - std::sqrt(5.0));  // golden angle (rad)
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n;
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden * i;
    p.emplace_back(rho * std::cos(phi), rho * std::sin(phi), z);
  }
  return p;
}

Tool::Tool(const ToolOptions& options) : m_options(options) {
  const double r = options.burr_radius_mm;
  if (!(r > 0.0) || !std::isfinite(r)) throw InvalidInput("tool: burr radius must be positive");
  if (options.sample_count < 20) throw InvalidInput("tool: at least 20 surface samples are needed");
  if (!(options.shaft_radius_mm >= 0.0) || options.shaft_radius_mm >= r) {
    throw InvalidInput("tool: shaft radius must be ≥ 0 and smaller than the burr radius");
  }
  for (const Vec3& u : fibonacci_sphere(options.sample_count)) m_burr.push_back(r * u);
  const double rs = options.shaft_radius_mm;
  if (rs > 0.0) {
    if (!(options.shaft_length_mm > 0.0)) throw InvalidInput("tool: shaft length must be positive");
    const double spacing = std::sqrt(4.0 * kPi * r * r / options.sample_count);
    m_ring = std::max(6, static_cast<int>(std::ceil(2.0 * kPi * rs / spacing)));
    const double z0 = std::sqrt(r * r - rs * rs);  // where the shaft leaves the burr
    for (double z = z0 + 0.5 * spacing; z <= options.shaft_length_mm; z += spacing) {
      for (int k = 0; k < m_ring; ++k) {
        const double a = 2.0 * kPi * k / m_ring;
        m_shaft.emplace_back(rs * std::cos(a), rs * std::sin(a), z);
      }
    }
  }
}

ToolOptions parse_tool(std::string_view spec) {
  const std::string text(spec);
  if (!spec.starts_with("sphere:")) {
    throw InvalidInput("--tool '" + text + "': expected sphere:radius=MM[,shaft=MM][,samples=N]");
  }
  ToolOptions o;
  bool radius = false;
  std::string_view rest = spec.substr(7);
  while (!rest.empty()) {
    const auto comma = rest.find(',');
    const std::string_view item = rest.substr(0, comma);
    const auto eq = item.find('=');
    if (eq == std::string_view::npos) throw InvalidInput("--tool '" + text + "': '" + std::string(item) + "' is not key=value");
    const std::string_view key = item.substr(0, eq), value = item.substr(eq + 1);
    double v = 0.0;
    const auto [ptr, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
    if (ec != std::errc() || ptr != value.data() + value.size() || !std::isfinite(v)) {
      throw InvalidInput("--tool '" + text + "': '" + std::string(value) + "' is not a number");
    }
    if (key == "radius") {
      o.burr_radius_mm = v;
      radius = true;
    } else if (key == "shaft") {
      o.shaft_radius_mm = v;
    } else if (key == "samples") {
      o.sample_count = static_cast<int>(v);
    } else {
      throw InvalidInput("--tool '" + text + "': unknown key '" + std::string(key) + "'");
    }
    if (comma == std::string_view::npos) break;
    rest = rest.substr(comma + 1);
  }
  if (!radius) throw InvalidInput("--tool '" + text + "': radius=MM is required");
  (void)Tool(o);  // validates
  return o;
}

}  // namespace ido::drill
