// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstddef>
#include <string>

/// The VTK peer of bench_marching_cubes, in its own translation unit because VTK 9.1's
/// vtkSMPTools.h does not compile as C++20 (it is built as C++17).
namespace ido::bench {

struct PeerResult {
  std::size_t vertices = 0;
  std::size_t triangles = 0;
};

/// Sets VTK's SMP thread count (0 = the backend default) and describes the backend.
std::string vtk_set_threads(int threads);

/// Keeps a vtkImageData wrapping @p values (n³ floats, 1 mm voxels, no copy) between calls.
void vtk_prepare(const float* values, int n);

/// One vtkFlyingEdges3D run at @p iso on the prepared image.
PeerResult vtk_flying_edges(double iso);

}  // namespace ido::bench
