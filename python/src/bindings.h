// SPDX-License-Identifier: Apache-2.0
// The Python module `ido` (pybind11): what each binding file registers.
// Presentation only: every algorithm is the C++ library's; these files convert between
// numpy arrays / Python values and the library's types, and release the GIL around long calls.
#pragma once
#include <pybind11/pybind11.h>

#include "ido/io/report_json.h"

namespace ido::python {

/// A report as Python values (dict, list, float, int, bool, None), through the library's one
/// JSON form of it (io::to_json), so Python's keys are the CLI's.
[[nodiscard]] inline pybind11::object to_python(const io::Json& report) {
  return pybind11::module_::import("json").attr("loads")(report.dump());
}

/// ido.Volume (float32 voxels), ido.Mask (uint8 voxels), read_volume, write_volume.
void bind_volume(pybind11::module_& m);
/// ido.TriangleMesh, ido.TetMesh, mesh files, checks, self-intersections, marching cubes,
/// tetrahedralisation.
void bind_mesh(pybind11::module_& m);
/// ido.phantom, ido.segment (the balloon), surface_to_mask, compare, compare_mesh.
void bind_segment(pybind11::module_& m);
/// ido.World (the simulation library), beam and sphere generators, ido.Scene / load_scene.
void bind_sim(pybind11::module_& m);

}  // namespace ido::python
