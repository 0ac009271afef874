// SPDX-License-Identifier: Apache-2.0
#include "ido/io/memory_budget.h"

#include <sys/resource.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "ido/core/error.h"

namespace ido::io {
namespace {
std::atomic<std::uint64_t> g_limit{0};  // 0: the default
constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();
}  // namespace

std::uint64_t default_memory_limit_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page = sysconf(_SC_PAGE_SIZE);
  std::uint64_t limit = pages > 0 && page > 0
                            ? static_cast<std::uint64_t>(pages) / 4 * 3 * static_cast<std::uint64_t>(page)
                            : std::uint64_t(4) << 30;
  rlimit as{};
  if (getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY)
    limit = std::min<std::uint64_t>(limit, static_cast<std::uint64_t>(as.rlim_cur) / 2);
  return limit;
}

std::uint64_t memory_limit_bytes() {
  const std::uint64_t set = g_limit.load(std::memory_order_relaxed);
  return set != 0 ? set : default_memory_limit_bytes();
}

void set_memory_limit_bytes(std::uint64_t bytes) { g_limit.store(bytes, std::memory_order_relaxed); }

void check_memory_budget(const std::string& name, std::uint64_t bytes, std::string_view what) {
  const std::uint64_t limit = memory_limit_bytes();
  if (bytes > limit)
    throw IoError(name, fmt::format("{} need {}, over the memory limit of {}", what,
                                    bytes == kMax ? std::string("more than 16 EiB") : format_bytes(bytes),
                                    format_bytes(limit)));
}

std::uint64_t saturating_product(std::initializer_list<std::uint64_t> factors) {
  std::uint64_t p = 1;
  for (const auto f : factors) {
    if (f == 0) return 0;
    if (p > kMax / f) return kMax;
    p *= f;
  }
  return p;
}

std::string format_bytes(std::uint64_t bytes) {
  static const char* const kUnits[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  double v = static_cast<double>(bytes);
  int u = 0;
  while (v >= 1024.0 && u < 6) {
    v /= 1024.0;
    ++u;
  }
  if (u == 0) return fmt::format("{} B", bytes);
  return fmt::format("{:.3g} {}", v, kUnits[u]);
}

std::uint64_t parse_memory_size(std::string_view text, std::string_view what) {
  auto bad = [&] {
    return InvalidInput(fmt::format("{}: '{}' is not a memory size (e.g. 12G, 512M, 1.5GiB)", what, text));
  };
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || !std::isfinite(value) || !(value > 0.0)) throw bad();
  std::string unit(end, text.data() + text.size());
  for (auto& c : unit) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  double scale = 1.0;
  if (!unit.empty() && unit != "B") {
    const std::string_view prefixes = "KMGT";
    const auto k = prefixes.find(unit[0]);
    if (k == std::string_view::npos) throw bad();
    const std::string rest = unit.substr(1);
    if (!rest.empty() && rest != "B" && rest != "IB") throw bad();
    scale = std::pow(1024.0, static_cast<double>(k + 1));
  }
  const double bytes = std::floor(value * scale);
  if (!(bytes >= 1.0) || bytes >= 1.8e19) throw bad();
  return static_cast<std::uint64_t>(bytes);
}

}  // namespace ido::io
