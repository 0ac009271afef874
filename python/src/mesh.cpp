// SPDX-License-Identifier: Apache-2.0
// ido.TriangleMesh / ido.TetMesh and the mesh functions of the library seen from Python.
// Vertices and cells are exposed as read-only numpy views; assigning a new array validates it
// (indices in range, finite coordinates) and copies it, so a mesh handed to the library is
// always well formed.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "arrays.h"
#include "bindings.h"
#include "ido/core/error.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/self_intersection.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/geometry/triangle_mesh.h"
#include "ido/io/mesh_io.h"
#include "ido/meshing/marching_cubes.h"
#include "ido/meshing/tetrahedralize.h"

namespace py = pybind11;

namespace ido::python {
namespace {

using Cells = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;

/// A read-only numpy view of @p rows rows of @p cols values at @p data, kept alive by @p owner.
template <class T>
py::array_t<T> rows_view(const T* data, std::size_t rows, py::ssize_t cols, const py::object& owner) {
  const auto s = py::ssize_t(sizeof(T));
  py::array_t<T> a = rows == 0 ? py::array_t<T>(std::vector<py::ssize_t>{0, cols})
                               : py::array_t<T>({py::ssize_t(rows), cols}, {cols * s, s}, data, owner);
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

/// Rows of @p N vertex indices, each in [0, vertex_count).
template <std::size_t N>
std::vector<std::array<std::int32_t, N>> cells_from_array(const Cells& a, std::size_t vertex_count, const char* what) {
  if (a.ndim() != 2 || a.shape(1) != py::ssize_t(N))
    throw InvalidInput(std::string(what) + ": expected an integer array of shape (n, " + std::to_string(N) + ")");
  std::vector<std::array<std::int32_t, N>> out(std::size_t(a.shape(0)));
  const std::int64_t* p = a.data();
  for (std::size_t i = 0; i < out.size(); ++i)
    for (std::size_t c = 0; c < N; ++c) {
      const std::int64_t v = p[N * i + c];
      if (v < 0 || std::uint64_t(v) >= vertex_count)
        throw InvalidInput(std::string(what) + ": row " + std::to_string(i) + " names vertex " + std::to_string(v) +
                           ", outside 0.." + std::to_string(std::int64_t(vertex_count) - 1));
      out[i][c] = std::int32_t(v);
    }
  return out;
}

}  // namespace

void bind_mesh(py::module_& m) {
  using geometry::TetMesh;
  using geometry::TriangleMesh;

  py::class_<TriangleMesh>(m, "TriangleMesh", "A triangle surface: vertices (n, 3) in mm, triangles (m, 3) of vertex indices.")
      .def(py::init([](const Points& vertices, const Cells& triangles) {
             TriangleMesh t;
             t.vertices = points_from_array(vertices, "TriangleMesh vertices");
             t.triangles = cells_from_array<3>(triangles, t.vertices.size(), "TriangleMesh triangles");
             return t;
           }),
           py::arg("vertices"), py::arg("triangles"),
           "A mesh from vertex coordinates (n, 3; mm) and triangles (m, 3; indices, counter-clockwise seen from "
           "outside). Copies both. Raises ValueError for a bad shape, an index out of range or a non-finite value.")
      .def_property(
          "vertices",
          [](py::object self) {
            const auto& t = self.cast<const TriangleMesh&>();
            return rows_view<double>(t.vertices.empty() ? nullptr : t.vertices.front().data(), t.vertices.size(), 3, self);
          },
          [](TriangleMesh& t, const Points& a) {
            auto v = points_from_array(a, "TriangleMesh vertices");
            for (const Tri& tri : t.triangles)
              for (std::int32_t i : tri)
                if (std::size_t(i) >= v.size())
                  throw InvalidInput("TriangleMesh vertices: the triangles name vertex " + std::to_string(i) +
                                     " but only " + std::to_string(v.size()) + " are given");
            t.vertices = std::move(v);
          },
          "Vertex coordinates (n, 3), mm; a read-only view. Assign an array to replace them.")
      .def_property(
          "triangles",
          [](py::object self) {
            const auto& t = self.cast<const TriangleMesh&>();
            return rows_view<std::int32_t>(t.triangles.empty() ? nullptr : t.triangles.front().data(), t.triangles.size(),
                                           3, self);
          },
          [](TriangleMesh& t, const Cells& a) {
            t.triangles = cells_from_array<3>(a, t.vertices.size(), "TriangleMesh triangles");
          },
          "Triangles (m, 3) as vertex indices (int32); a read-only view. Assign an array to replace them.")
      .def("__repr__", [](const TriangleMesh& t) {
        return "<ido.TriangleMesh " + std::to_string(t.vertices.size()) + " vertices, " +
               std::to_string(t.triangles.size()) + " triangles>";
      });

  py::class_<TetMesh>(m, "TetMesh", "A tetrahedral mesh: vertices (n, 3) in mm, tets (m, 4) of vertex indices.")
      .def(py::init([](const Points& vertices, const Cells& tets) {
             TetMesh t;
             t.vertices = points_from_array(vertices, "TetMesh vertices");
             t.tets = cells_from_array<4>(tets, t.vertices.size(), "TetMesh tets");
             return t;
           }),
           py::arg("vertices"), py::arg("tets"), "A mesh from vertex coordinates (n, 3; mm) and tetrahedra (m, 4). Copies both.")
      .def_property_readonly(
          "vertices",
          [](py::object self) {
            const auto& t = self.cast<const TetMesh&>();
            return rows_view<double>(t.vertices.empty() ? nullptr : t.vertices.front().data(), t.vertices.size(), 3, self);
          },
          "Vertex coordinates (n, 3), mm; a read-only view.")
      .def_property_readonly(
          "tets",
          [](py::object self) {
            const auto& t = self.cast<const TetMesh&>();
            return rows_view<std::int32_t>(t.tets.empty() ? nullptr : t.tets.front().data(), t.tets.size(), 4, self);
          },
          "Tetrahedra (m, 4) as vertex indices (int32); a read-only view.")
      .def("__repr__", [](const TetMesh& t) {
        return "<ido.TetMesh " + std::to_string(t.vertices.size()) + " vertices, " + std::to_string(t.tets.size()) +
               " tetrahedra>";
      });

  m.def(
      "read_triangle_mesh",
      [](const std::filesystem::path& path) {
        py::gil_scoped_release unlocked;
        return io::read_triangle_mesh(path);
      },
      py::arg("path"), "Reads a surface (.stl, .obj, .ply, .vtp). Raises OSError naming the file and the problem.");
  m.def(
      "read_tet_mesh",
      [](const std::filesystem::path& path) {
        py::gil_scoped_release unlocked;
        return io::read_tet_mesh(path);
      },
      py::arg("path"), "Reads a tetrahedral mesh (.vtu, .msh, TetGen .node/.ele).");
  m.def(
      "write_mesh",
      [](const std::filesystem::path& path, const TriangleMesh& mesh, bool ascii) {
        py::gil_scoped_release unlocked;
        io::write_triangle_mesh(path, mesh, {.ascii = ascii});
      },
      py::arg("path"), py::arg("mesh"), py::arg("ascii") = false,
      "Writes a surface (.stl, .obj, .ply, .vtp by extension), atomically.");
  m.def(
      "write_mesh",
      [](const std::filesystem::path& path, const TetMesh& mesh, bool ascii) {
        py::gil_scoped_release unlocked;
        io::write_tet_mesh(path, mesh, {.ascii = ascii});
      },
      py::arg("path"), py::arg("mesh"), py::arg("ascii") = false,
      "Writes a tetrahedral mesh (.vtu, .msh, .node by extension), atomically.");
  m.def(
      "check_mesh", [](const TriangleMesh& mesh) { return to_python(io::to_json(geometry::check_mesh(mesh))); }, py::arg("mesh"),
      "Closed, manifold and oriented flags, Euler characteristic, genus, components, area (mm²), enclosed volume "
      "(mm³) and bounds, as a dict.");
  m.def(
      "self_intersections",
      [](const TriangleMesh& mesh) {
        std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
        {
          py::gil_scoped_release unlocked;
          pairs = geometry::self_intersections(mesh);
        }
        py::array_t<std::int32_t> out({py::ssize_t(pairs.size()), py::ssize_t(2)});
        auto w = out.mutable_unchecked<2>();
        for (std::size_t i = 0; i < pairs.size(); ++i) {
          w(py::ssize_t(i), 0) = pairs[i].first;
          w(py::ssize_t(i), 1) = pairs[i].second;
        }
        return out;
      },
      py::arg("mesh"),
      "The pairs of triangles (k, 2) that intersect other than through a shared vertex or edge (exact predicates).");
  m.def(
      "marching_cubes",
      [](const image::Volume<float>& field, float iso) {
        py::gil_scoped_release unlocked;
        return meshing::marching_cubes(field, {.iso_value = iso});
      },
      py::arg("field"), py::arg("iso") = 0.0f,
      "The level set `iso` of the field (values below it inside) as a closed, 2-manifold, outward-oriented surface "
      "in world mm.");
  m.def(
      "marching_cubes",
      [](const image::Volume<std::uint8_t>& mask) {
        py::gil_scoped_release unlocked;
        return meshing::marching_cubes_mask(mask);
      },
      py::arg("mask"), "The boundary surface of the mask's non-zero voxels (closed, 2-manifold).");
  m.def(
      "tetrahedralize",
      [](const TriangleMesh& surface, double edge_mm, bool graded) {
        py::gil_scoped_release unlocked;
        return meshing::tetrahedralize_surface(surface, {.edge_mm = edge_mm, .graded = graded});
      },
      py::arg("surface"), py::arg("edge_mm") = 0.0, py::arg("graded") = false,
      "Fills a closed surface with tetrahedra by isosurface stuffing (Labelle & Shewchuk 2007): lattice edge "
      "edge_mm (0 = the surface's mean edge length), graded = coarser inside. Dihedral angles 10.78-164.83 degrees.");
}

}  // namespace ido::python
