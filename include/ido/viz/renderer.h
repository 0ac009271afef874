// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/aabb.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/geometry/triangle_mesh.h"
#include "ido/image/volume.h"
#include "ido/viz/camera.h"

namespace ido::viz {

/// An 8-bit RGBA picture, rows from top to bottom, 4 bytes per pixel.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;

  /// The 4 bytes of pixel (x, y), (0, 0) being the top-left corner.
  [[nodiscard]] const std::uint8_t* pixel(int x, int y) const {
    return rgba.data() + 4 * (std::size_t(y) * std::size_t(width) + std::size_t(x));
  }
};

/// Writes @p image as an 8-bit RGBA PNG (libpng), atomically.
/// @throws ido::InvalidInput for an image whose buffer does not match its size;
///         ido::IoError when the file cannot be written.
void write_png(const std::filesystem::path& path, const Image& image);

/// Colour maps for scalar fields.
enum class Colormap {
  Viridis,   ///< perceptually uniform dark blue → green → yellow (van der Walt & Smith, matplotlib)
  CoolWarm,  ///< diverging blue → grey → red (Moreland, "Diverging color maps", ISVC 2009)
};

/// The colour (RGB in [0, 1]) of @p t ∈ [0, 1] (clamped) in @p map.
[[nodiscard]] Vec3 colormap_rgb(Colormap map, double t);

/// How a surface is shaded.
enum class Shading {
  Flat,    ///< one normal per triangle
  Smooth,  ///< area-weighted vertex normals, interpolated (Gouraud)
};

/// Options of Renderer::add_surface.
struct SurfaceOptions {
  Shading shading = Shading::Smooth;
  bool two_sided = true;  ///< light back faces too (open or inward-facing surfaces)
};

/// A plane through @p point (mm) with normal @p normal; the clipped side is where
/// (x − point) · normal > 0.
struct ClipPlane {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3(1, 0, 0);
};

/// Options of Renderer::add_tet_mesh_clipped.
struct TetClipOptions {
  Colormap colormap = Colormap::Viridis;
  /// Value range mapped to the colour map's ends; unset = the field's min and max.
  std::optional<double> range_min;
  std::optional<double> range_max;
  Vec3 uniform_colour = Vec3(0.8, 0.8, 0.8);  ///< used when no field is named
  /// Draw the edges of the drawn faces as lines, so the tetrahedra can be told apart.
  bool edges = false;
  Vec3 edge_colour = Vec3(0.1, 0.1, 0.1);
};

/// Display window of a CT slice: grey = (value − (level − window/2)) / window, clamped.
struct SliceOptions {
  double window = 0;  ///< width of the displayed value range; ≤ 0 = the slice's min..max
  double level = 0;   ///< centre of the displayed value range
};

/// Draws triangle meshes, clipped tetrahedral meshes and volume slices with OpenGL rendered
/// off-screen by Mesa's OSMesa (software, no display needed) and returns or writes the
/// picture. Lighting: one white directional light from the camera (headlight), ambient 0.25
/// plus Lambertian diffuse 0.75, so a face seen head-on shows exactly its colour.
/// Everything is in world coordinates (mm). Not thread-safe for one instance; separate
/// instances may render from separate threads (calls into OSMesa are serialised).
class Renderer {
 public:
  /// A renderer for pictures of @p width × @p height pixels.
  /// @throws ido::InvalidInput unless 1 ≤ width, height ≤ 16384.
  Renderer(int width, int height);

  [[nodiscard]] int width() const { return m_width; }
  [[nodiscard]] int height() const { return m_height; }

  /// Adds a triangle mesh with a uniform colour (RGB in [0, 1]).
  /// @throws ido::InvalidInput for an index out of range.
  void add_surface(const geometry::TriangleMesh& mesh, const Vec3& colour_rgb,
                   const SurfaceOptions& options = {});

  /// Adds the tetrahedra of @p mesh whose centroid is not on the clipped side of @p plane,
  /// drawing the boundary faces of that set, each coloured by its tetrahedron's value of the
  /// cell field @p cell_field (first component) through options.colormap; an empty field name
  /// draws options.uniform_colour.
  /// @throws ido::InvalidInput if the field is missing, has the wrong size, or an index is
  ///         out of range.
  void add_tet_mesh_clipped(const geometry::TetMesh& mesh, const ClipPlane& plane,
                            const std::string& cell_field, const TetClipOptions& options = {});

  /// Adds slice @p index along @p axis (0 = i, 1 = j, 2 = k) of @p volume as a quad in world
  /// space spanning the slice's voxels edge to edge, one texel per voxel (nearest).
  /// @throws ido::InvalidInput for an empty volume, a bad axis or an index out of range.
  void add_slice(const image::Volume<float>& volume, int axis, std::int64_t index,
                 const SliceOptions& options = {});

  /// Marks the contour pixels of @p mask on the slices added with add_slice that lie on the
  /// same grid, axis and index: a voxel of the slice is a contour voxel when it is in the
  /// mask (nonzero) and one of its 4 in-slice neighbours is not (or lies outside the grid).
  /// Those texels are painted @p colour_rgb.
  /// @throws ido::InvalidInput if no added slice matches (grid, axis, index).
  void add_contour(const image::Volume<std::uint8_t>& mask, int axis, std::int64_t index,
                   const Vec3& colour_rgb = Vec3(1, 0.15, 0.1));

  /// The camera used by render(); until set, one fitted with Camera::orbit(az 30°, el 20°,
  /// perspective) around everything added, at render time.
  void set_camera(const Camera& camera) { m_camera = camera; }
  /// A camera fitted to everything added so far (see Camera::orbit).
  [[nodiscard]] Camera fit_camera(double azimuth_deg, double elevation_deg,
                                  Projection projection = Projection::Perspective) const;
  /// A camera looking straight at slice number @p slice (in order of add_slice), orthographic,
  /// with the slice filling the picture's height (or width), the voxel index axes shown
  /// left→right and top→bottom.
  /// @throws ido::InvalidInput if there is no such slice.
  [[nodiscard]] Camera slice_camera(std::size_t slice = 0) const;

  /// Background colour (RGB in [0, 1]), default white.
  void set_background(const Vec3& rgb) { m_background = rgb; }

  /// Axis-aligned bounds (mm) of everything added; a zero box when empty.
  [[nodiscard]] geometry::Aabb bounds() const;

  /// Renders the scene. @throws ido::Error if OSMesa cannot create a context.
  [[nodiscard]] Image render() const;

  /// Renders and writes a PNG. @throws as render() and write_png().
  void write_png(const std::filesystem::path& path) const;

 private:
  struct Vertex {
    Eigen::Vector3f position;
    Eigen::Vector3f normal;
    Eigen::Vector3f colour;
  };
  struct Slice {
    image::Volume<float> grid;  // placement only (spacing, origin, direction), one voxel
    Index3 grid_size{0, 0, 0};  // the sliced volume's size
    int axis = 2;
    std::int64_t index = 0;
    int tex_w = 0, tex_h = 0;
    std::vector<std::uint8_t> texels;  // RGB, tex_w × tex_h, row v = second in-slice axis
    std::array<Vec3, 4> corners;       // world quad, texel (0,0) corner first
  };

  int m_width;
  int m_height;
  std::vector<Vertex> m_triangles;  // 3 per triangle, lit at render time
  std::vector<bool> m_two_sided;    // per triangle
  std::vector<std::array<Eigen::Vector3f, 3>> m_lines;  // segment ends and colour, unlit
  std::vector<Slice> m_slices;
  std::optional<Camera> m_camera;
  Vec3 m_background = Vec3::Ones();
  geometry::Aabb m_bounds;  // of everything added

  void grow_bounds(const Vec3& p);
};

}  // namespace ido::viz
