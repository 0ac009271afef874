// SPDX-License-Identifier: Apache-2.0
// ido.Volume / ido.Mask: the library's image::Volume<float> / Volume<uint8_t> seen from Python.
// The voxels are exposed as a numpy view of shape (nz, ny, nx), indexed [k, j, i] (the order
// SimpleITK's GetArrayFromImage uses), sharing memory with the volume.
#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "ido/core/error.h"
#include "ido/image/volume.h"
#include "ido/io/volume_io.h"

namespace py = pybind11;

namespace ido::python {
namespace {

template <class T>
using Array3 = py::array_t<T, py::array::c_style | py::array::forcecast>;

/// The volume of @p voxels (shape (nz, ny, nx)) with the given geometry.
template <class T>
image::Volume<T> volume_from_array(const Array3<T>& voxels, const Vec3& spacing, const Vec3& origin,
                                   const std::optional<Mat3>& direction) {
  if (voxels.ndim() != 3)
    throw InvalidInput("a volume needs a 3-D array of shape (nz, ny, nx); got " + std::to_string(voxels.ndim()) +
                       " dimensions");
  const Index3 size{voxels.shape(2), voxels.shape(1), voxels.shape(0)};
  if (size[0] <= 0 || size[1] <= 0 || size[2] <= 0) throw InvalidInput("a volume needs at least one voxel along each axis");
  std::vector<T> data(voxels.data(), voxels.data() + voxels.size());
  return image::Volume<T>(size, std::move(data), spacing, origin, direction.value_or(Mat3::Identity()));
}

/// A numpy view of @p v's voxels, shape (nz, ny, nx), kept alive by @p owner.
template <class T>
py::array_t<T> voxel_view(image::Volume<T>& v, const py::object& owner) {
  const auto nx = py::ssize_t(v.size(0)), ny = py::ssize_t(v.size(1)), nz = py::ssize_t(v.size(2));
  const auto s = py::ssize_t(sizeof(T));
  return py::array_t<T>({nz, ny, nx}, {nx * ny * s, nx * s, s}, v.data().data(), owner);
}

template <class T>
void bind_volume_type(py::module_& m, const char* name, const char* doc) {
  using V = image::Volume<T>;
  py::class_<V>(m, name, doc)
      .def(py::init([](const Array3<T>& voxels, const Vec3& spacing, const Vec3& origin, const std::optional<Mat3>& direction) {
             return volume_from_array<T>(voxels, spacing, origin, direction);
           }),
           py::arg("voxels"), py::arg("spacing") = Vec3(Vec3::Ones()), py::arg("origin") = Vec3(Vec3::Zero()),
           py::arg("direction") = py::none(),
           "A volume from a 3-D array of shape (nz, ny, nx) (copied), the voxel spacing (mm, per axis i, j, k), "
           "the world position of voxel (0, 0, 0) (mm, LPS) and the 3x3 direction matrix (columns: the i, j, k "
           "axes in world; identity by default). Raises ValueError for a bad shape or geometry.")
      .def_property_readonly(
          "array", [](py::object self) { return voxel_view<T>(self.cast<V&>(), self); },
          "The voxels as a writable numpy view of shape (nz, ny, nx), indexed [k, j, i]; shares memory with the "
          "volume.")
      .def_property_readonly(
          "size", [](const V& v) { return py::make_tuple(v.size(0), v.size(1), v.size(2)); },
          "Voxel counts (nx, ny, nz) along i, j, k (the reverse of array.shape).")
      .def_property("spacing", &V::spacing, &V::set_spacing, "Voxel size along i, j, k (mm).")
      .def_property("origin", &V::origin, &V::set_origin, "World position of voxel (0, 0, 0) (mm, LPS).")
      .def_property("direction", &V::direction, &V::set_direction,
                    "3x3 matrix whose columns are the i, j, k axes in world coordinates.")
      .def(
          "index_to_world", [](const V& v, const Vec3& ijk) { return Vec3(v.index_to_world(ijk)); }, py::arg("ijk"),
          "World position (mm) of the continuous voxel index (i, j, k).")
      .def(
          "world_to_index", [](const V& v, const Vec3& xyz) { return Vec3(v.world_to_index(xyz)); }, py::arg("xyz"),
          "Continuous voxel index (i, j, k) of the world position (mm).")
      .def(
          "same_grid", [](const V& v, const image::Volume<float>& other) { return v.same_grid(other); },
          py::arg("other"), "Whether the two volumes have the same size, spacing, origin and direction.")
      .def(
          "same_grid", [](const V& v, const image::Volume<std::uint8_t>& other) { return v.same_grid(other); },
          py::arg("other"))
      .def("__repr__", [name](const V& v) {
        return std::string("<ido.") + name + " " + std::to_string(v.size(0)) + "x" + std::to_string(v.size(1)) + "x" +
               std::to_string(v.size(2)) + " spacing (" + std::to_string(v.spacing()[0]) + ", " +
               std::to_string(v.spacing()[1]) + ", " + std::to_string(v.spacing()[2]) + ") mm>";
      });
  // A numpy array is taken wherever this type is (unit spacing, origin 0, identity direction),
  // through the constructor above.
  py::implicitly_convertible<py::array, V>();
}

}  // namespace

void bind_volume(py::module_& m) {
  bind_volume_type<float>(m, "Volume", "A 3-D image of float32 voxels with its geometry (spacing, origin, direction; mm).");
  bind_volume_type<std::uint8_t>(m, "Mask", "A 3-D label image of uint8 voxels (non-zero = inside) with its geometry.");

  m.def(
      "read_volume",
      [](const std::filesystem::path& path) {
        py::gil_scoped_release unlocked;
        return io::read_volume(path);
      },
      py::arg("path"),
      "Reads a volume (NIfTI, NRRD, MetaImage, or a DICOM folder) as float32 voxels in the file's units (e.g. HU). "
      "Raises OSError naming the file when it cannot be read.");
  m.def(
      "read_mask",
      [](const std::filesystem::path& path, std::optional<double> label, std::optional<double> below) {
        if (label && below) throw InvalidInput("read_mask: give label or below, not both");
        py::gil_scoped_release unlocked;
        const image::Volume<float> v = io::read_volume(path);
        auto out = v.like<std::uint8_t>(0);
        for (std::size_t q = 0; q < v.voxel_count(); ++q) {
          const double x = v.data()[q];
          out.data()[q] = (label ? x == *label : below ? x < *below : x != 0.0) ? 1 : 0;
        }
        return out;
      },
      py::arg("path"), py::kw_only(), py::arg("label") = py::none(), py::arg("below") = py::none(),
      "Reads a volume as a mask: 1 where the voxel is non-zero, or equals `label` (a label map), or lies below "
      "`below` (a level set, e.g. VMTK's, inside where negative); 0 elsewhere.");
  m.def(
      "write_volume",
      [](const std::filesystem::path& path, const image::Volume<float>& v) {
        py::gil_scoped_release unlocked;
        io::write_volume(path, v);
      },
      py::arg("path"), py::arg("volume"),
      "Writes a float32 volume (format by extension: .nii, .nii.gz, .nrrd, .mha, .mhd), atomically.");
  m.def(
      "write_volume",
      [](const std::filesystem::path& path, const image::Volume<std::uint8_t>& v) {
        py::gil_scoped_release unlocked;
        io::write_volume(path, v);
      },
      py::arg("path"), py::arg("mask"), "Writes a uint8 mask, atomically.");
}

}  // namespace ido::python
