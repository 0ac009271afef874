// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <filesystem>
#include <utility>
#include <vector>

#include "ido/core/math.h"
#include "ido/image/volume.h"

namespace ido::io {

/// What kind of data a path holds, judged by its extension (or being a folder); a Gmsh .msh
/// file is read to tell a tetrahedral mesh from a triangle-only surface.
enum class FileKind {
  Volume,        ///< .nii, .nii.gz, .nrrd, .nhdr, .mha, .mhd, or a DICOM folder
  TriangleMesh,  ///< .stl, .obj, .ply, .vtp, or a .msh holding triangles only
  TetMesh,       ///< .vtu, .msh (with tetrahedra), .node, .ele
};

/// The kind of file at @p path. A folder counts as a DICOM volume unless its name ends in a
/// mesh extension (then the mesh reader reports "is a folder").
/// @throws ido::IoError naming the path when the extension is unknown.
[[nodiscard]] FileKind file_kind(const std::filesystem::path& path);

/// Intensity statistics of a volume (in the volume's units, e.g. HU).
struct VolumeStatistics {
  double min = 0.0;
  double max = 0.0;
  double mean = 0.0;
  double stddev = 0.0;  ///< population standard deviation
  /// (percent, value) pairs for 1, 5, 25, 50, 75, 95 and 99 % (ido::percentile's definition).
  std::vector<std::pair<double, double>> percentiles;
};

/// Range, mean, standard deviation and percentiles of all voxels.
/// @throws ido::InvalidInput for an empty volume.
[[nodiscard]] VolumeStatistics volume_statistics(const image::Volume<float>& volume);


}  // namespace ido::io
