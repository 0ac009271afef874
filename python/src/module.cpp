// SPDX-License-Identifier: Apache-2.0
// The Python module `ido`: numpy in and out, the C++ library underneath.
// Errors map onto Python's: ido::InvalidInput → ValueError, ido::IoError → OSError (its
// message names the file; FileNotFoundError when that file or its folder does not exist, as
// Python's own open() raises), ido::Cancelled → KeyboardInterrupt, any other ido::Error →
// RuntimeError.
#include <filesystem>
#include <system_error>

#include <pybind11/pybind11.h>

#include "bindings.h"
#include "ido/core/error.h"

namespace py = pybind11;

// The extension is ido._ido, re-exported by the package's __init__.py. Its classes are named
// while the module calls itself "ido", so that they are ido.Volume, ido.World, ... (in
// signatures and type names), as users import them; the name is restored afterwards.
PYBIND11_MODULE(_ido, m) {
  const py::object own_name = m.attr("__name__");
  m.attr("__name__") = "ido";
  m.doc() =
      "ido: computer-assisted surgery toolkit (Turini et al. 2007) — volumes and meshes as numpy arrays, balloon "
      "segmentation, phantoms and accuracy metrics, marching cubes and tetrahedral meshing, and the deformable-"
      "objects simulation library (particles, force models, switchable integrators, one call per step).";
  m.attr("__version__") = IDO_VERSION;
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ido::InvalidInput& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const ido::IoError& e) {
      std::error_code ec;
      const bool missing = !e.path().empty() && !std::filesystem::exists(e.path(), ec);
      PyErr_SetString(missing ? PyExc_FileNotFoundError : PyExc_OSError, e.what());
    } catch (const ido::Cancelled& e) {
      PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
    }
  });
  ido::python::bind_volume(m);
  ido::python::bind_mesh(m);
  ido::python::bind_segment(m);
  ido::python::bind_sim(m);
  m.attr("__name__") = own_name;
}
