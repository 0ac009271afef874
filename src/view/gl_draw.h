// SPDX-License-Identifier: Apache-2.0
#pragma once
// OpenGL 3.3 core drawing for the workbench (private to src/view): three shader programs
// (lit triangles, coloured lines, windowed grey-level textures) and the buffers they draw.
// Functions come from Mesa's libGL (GL_GLEXT_PROTOTYPES), which exports the core profile.

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "ido/core/math.h"
#include "ido/geometry/triangle_mesh.h"

namespace ido::view::gl {

using Mat4f = Eigen::Matrix4f;

/// How many uploads (MeshBuffer, LineBuffer, SliceQuad) this process has made: a picture drawn
/// from buffers is unchanged while this count is (the workbench's 3-D view cache).
[[nodiscard]] std::uint64_t upload_count() noexcept;

/// Triangles with per-vertex positions (mm), normals and colours, drawn lit by a headlight.
class MeshBuffer {
 public:
  MeshBuffer();
  ~MeshBuffer();
  MeshBuffer(const MeshBuffer&) = delete;
  MeshBuffer& operator=(const MeshBuffer&) = delete;
  /// Uploads @p mesh in one colour (RGB 0..1) with smooth (area-weighted) vertex normals, drawn
  /// indexed (each vertex shaded once), or one normal per triangle if @p flat.
  void upload(const geometry::TriangleMesh& mesh, const Vec3& colour, bool flat = false);
  /// Uploads @p mesh with one colour per vertex (RGB 0..1) and one normal per triangle.
  void upload_coloured(const geometry::TriangleMesh& mesh, const std::vector<Vec3>& vertex_colours);
  /// The triangle corners drawn (3 per triangle).
  [[nodiscard]] GLsizei vertex_count() const { return m_count; }
  void draw() const;

 private:
  GLuint m_vao = 0, m_vbo = 0, m_ebo = 0;
  GLsizei m_count = 0;
  bool m_indexed = false;  // drawn through the element buffer
};

/// Coloured line segments (pairs of points) or points.
class LineBuffer {
 public:
  LineBuffer();
  ~LineBuffer();
  LineBuffer(const LineBuffer&) = delete;
  LineBuffer& operator=(const LineBuffer&) = delete;
  void clear() { m_data.clear(); }
  /// Adds a segment from @p a to @p b in colour @p rgb.
  void add(const Vec3& a, const Vec3& b, const Vec3& rgb);
  /// Uploads what was added since clear().
  void upload();
  void draw() const;

 private:
  std::vector<float> m_data;
  GLuint m_vao = 0, m_vbo = 0;
  GLsizei m_count = 0;
};

/// A quad textured with a float image shown through a window / level.
class SliceQuad {
 public:
  SliceQuad();
  ~SliceQuad();
  SliceQuad(const SliceQuad&) = delete;
  SliceQuad& operator=(const SliceQuad&) = delete;
  /// Uploads a @p width × @p height float image (rows of width values, first row at t = 0).
  void upload_image(int width, int height, const std::vector<float>& values);
  /// Sets the corners (positions at texture (0,0), (1,0), (1,1), (0,1)).
  void set_corners(const std::array<Vec3, 4>& corners);
  void draw() const;

 private:
  GLuint m_vao = 0, m_vbo = 0, m_texture = 0;
};

/// The three programs. Create after the GL context is current.
class Painter {
 public:
  Painter();
  ~Painter();
  Painter(const Painter&) = delete;
  Painter& operator=(const Painter&) = delete;
  /// Draws lit triangles: @p mvp world → clip, @p view world → eye (for the headlight); only
  /// where dot(@p clip, (x, 1)) ≥ 0 (the default keeps everything). With @p cull_back the
  /// triangles seen from behind (clockwise on screen) are skipped: for a closed surface whose
  /// triangles are counter-clockwise seen from outside, which then looks the same at half the
  /// rasterising.
  void draw_mesh(const MeshBuffer& mesh, const Mat4f& mvp, const Mat4f& view,
                 const Eigen::Vector4f& clip = Eigen::Vector4f(0, 0, 0, 1), bool cull_back = false) const;
  void draw_lines(const LineBuffer& lines, const Mat4f& mvp) const;
  /// grey = (value − (level − window/2)) / window, clamped to 0..1.
  void draw_slice(const SliceQuad& quad, const Mat4f& mvp, double window, double level) const;

 private:
  GLuint m_mesh = 0, m_lines = 0, m_slice = 0;
};

/// The pixels (RGBA, rows top to bottom) of the bound @p width × @p height framebuffer: the
/// window's back buffer, or a framebuffer object's first colour attachment.
[[nodiscard]] std::vector<std::uint8_t> read_pixels(int width, int height);

}  // namespace ido::view::gl
