// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace ido::geometry {

/// A named per-point or per-cell attribute: `components` values per entity, stored
/// entity-major (values[e * components + c]). Units belong in the field's name or in the
/// documentation of whoever produces it (e.g. "displacement_mm", "von_mises_pa").
struct Field {
  int components = 1;
  std::vector<double> values;

  /// Number of entities the field covers.
  [[nodiscard]] std::size_t count() const {
    return components > 0 ? values.size() / static_cast<std::size_t>(components) : 0;
  }
};

/// Fields by name; ordered so that files are written deterministically.
using FieldMap = std::map<std::string, Field>;

}  // namespace ido::geometry
