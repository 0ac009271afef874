// SPDX-License-Identifier: Apache-2.0
// numpy ↔ point lists, shared by the binding files.
#pragma once
#include <string>
#include <vector>

#include <pybind11/numpy.h>

#include "ido/core/error.h"
#include "ido/core/math.h"

namespace ido::python {

/// An (n, 3) float64 array as numpy gives it (C order; other dtypes converted).
using Points = pybind11::array_t<double, pybind11::array::c_style | pybind11::array::forcecast>;

/// The rows of @p a as points. @throws ido::InvalidInput naming @p what for a shape other
/// than (n, 3) or a non-finite row.
inline std::vector<Vec3> points_from_array(const Points& a, const char* what) {
  if (a.ndim() != 2 || a.shape(1) != 3) throw InvalidInput(std::string(what) + ": expected an array of shape (n, 3)");
  std::vector<Vec3> out(std::size_t(a.shape(0)));
  const double* p = a.data();
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = Vec3(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    if (!out[i].allFinite()) throw InvalidInput(std::string(what) + ": row " + std::to_string(i) + " is not finite");
  }
  return out;
}

/// @p v as a new (n, 3) float64 array.
inline pybind11::array_t<double> points_to_array(const std::vector<Vec3>& v) {
  pybind11::array_t<double> out({pybind11::ssize_t(v.size()), pybind11::ssize_t(3)});
  double* o = out.mutable_data();
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int c = 0; c < 3; ++c) o[3 * i + std::size_t(c)] = v[i][c];
  return out;
}

}  // namespace ido::python
