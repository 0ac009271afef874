// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>

namespace ido::io {

/// The memory budget: the most bytes a single buffer whose size a file declares (a volume's
/// voxels, a mesh file's bytes, a DICOM series) may take. Every reader checks a declared size
/// against it before allocating, so a header that claims 512000 × 512000 × 300 voxels is
/// refused with a message rather than answered with std::bad_alloc or the OOM killer.
///
/// The default is three quarters of the physical memory, and no more than half the
/// address-space limit (RLIMIT_AS) when one is set (readers hold a file's bytes and their
/// decoded copy at once). set_memory_limit_bytes() overrides it for the whole process
/// (the `ido --memory-limit` option). Thread-safe.
[[nodiscard]] std::uint64_t memory_limit_bytes();

/// Sets the process-wide budget in bytes; 0 restores the default.
void set_memory_limit_bytes(std::uint64_t bytes);

/// The default budget described at memory_limit_bytes().
[[nodiscard]] std::uint64_t default_memory_limit_bytes();

/// @throws ido::IoError naming @p name when @p bytes exceed memory_limit_bytes(); the message
/// reads "<name>: <what> need 290 GiB, over the memory limit of 12 GiB".
void check_memory_budget(const std::string& name, std::uint64_t bytes, std::string_view what);

/// The product of @p factors, or UINT64_MAX when it overflows (declared sizes multiply).
[[nodiscard]] std::uint64_t saturating_product(std::initializer_list<std::uint64_t> factors);

/// "512 B", "3.1 MiB", "290 GiB": a byte count for messages.
[[nodiscard]] std::string format_bytes(std::uint64_t bytes);

/// Parses a size such as "12G", "512MiB", "1.5GB", "800M" or "1048576" (bytes; K/M/G/T are
/// binary multiples, with or without "B"/"iB"). @throws ido::InvalidInput naming @p what on
/// anything else, zero, or an overflow.
[[nodiscard]] std::uint64_t parse_memory_size(std::string_view text, std::string_view what);

}  // namespace ido::io
