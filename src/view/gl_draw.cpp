// SPDX-License-Identifier: Apache-2.0
#include "gl_draw.h"

#include <cstddef>
#include <string>

#include "ido/core/error.h"

namespace ido::view::gl {
namespace {

constexpr const char* kMeshVs = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec3 colour;
uniform mat4 mvp;
uniform mat4 view;
uniform vec4 clip;  // kept where dot(clip, (position, 1)) >= 0
out vec3 v_normal;
out vec3 v_colour;
void main() {
  gl_Position = mvp * vec4(position, 1.0);
  gl_ClipDistance[0] = dot(clip, vec4(position, 1.0));
  v_normal = mat3(view) * normal;
  v_colour = colour;
})";
// Headlight: ambient 0.25 + Lambertian 0.75, both sides lit (as viz::Renderer).
constexpr const char* kMeshFs = R"(#version 330 core
in vec3 v_normal;
in vec3 v_colour;
out vec4 frag;
void main() {
  float d = length(v_normal) > 0.0 ? abs(normalize(v_normal).z) : 1.0;
  frag = vec4(v_colour * (0.25 + 0.75 * d), 1.0);
})";
constexpr const char* kLineVs = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 colour;
uniform mat4 mvp;
out vec3 v_colour;
void main() {
  gl_Position = mvp * vec4(position, 1.0);
  v_colour = colour;
})";
constexpr const char* kLineFs = R"(#version 330 core
in vec3 v_colour;
out vec4 frag;
void main() { frag = vec4(v_colour, 1.0); })";
constexpr const char* kSliceVs = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec2 uv;
uniform mat4 mvp;
out vec2 v_uv;
void main() {
  gl_Position = mvp * vec4(position, 1.0);
  v_uv = uv;
})";
constexpr const char* kSliceFs = R"(#version 330 core
in vec2 v_uv;
uniform sampler2D image;
uniform float low;
uniform float width;
out vec4 frag;
void main() {
  float g = clamp((texture(image, v_uv).r - low) / width, 0.0, 1.0);
  frag = vec4(g, g, g, 1.0);
})";

GLuint compile(GLenum type, const char* source) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &source, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    std::string log(1024, '\0');
    glGetShaderInfoLog(s, GLsizei(log.size()), nullptr, log.data());
    throw Error("OpenGL shader does not compile: " + std::string(log.c_str()));
  }
  return s;
}

GLuint link(const char* vs, const char* fs) {
  const GLuint p = glCreateProgram();
  const GLuint v = compile(GL_VERTEX_SHADER, vs), f = compile(GL_FRAGMENT_SHADER, fs);
  glAttachShader(p, v);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) throw Error("OpenGL program does not link");
  return p;
}

void attribute(GLuint index, GLint components, GLsizei stride_floats, std::size_t offset_floats) {
  glEnableVertexAttribArray(index);
  glVertexAttribPointer(index, components, GL_FLOAT, GL_FALSE, stride_floats * GLsizei(sizeof(float)),
                        reinterpret_cast<const void*>(offset_floats * sizeof(float)));
}

std::uint64_t g_uploads = 0;  // the render thread's (GL calls are made on one thread)

}  // namespace

std::uint64_t upload_count() noexcept { return g_uploads; }

MeshBuffer::MeshBuffer() {
  glGenVertexArrays(1, &m_vao);
  glGenBuffers(1, &m_vbo);
  glGenBuffers(1, &m_ebo);
  glBindVertexArray(m_vao);
  glBindBuffer(GL_ARRAY_BUFFER, m_vbo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m_ebo);  // kept by the vertex array
  attribute(0, 3, 9, 0);
  attribute(1, 3, 9, 3);
  attribute(2, 3, 9, 6);
  glBindVertexArray(0);
}

MeshBuffer::~MeshBuffer() {
  glDeleteBuffers(1, &m_ebo);
  glDeleteBuffers(1, &m_vbo);
  glDeleteVertexArrays(1, &m_vao);
}

void MeshBuffer::upload(const geometry::TriangleMesh& mesh, const Vec3& colour, bool flat) {
  ++g_uploads;
  std::vector<Vec3> normals(mesh.vertices.size(), Vec3::Zero());
  for (const Tri& t : mesh.triangles) {
    const Vec3 n = (mesh.vertices[std::size_t(t[1])] - mesh.vertices[std::size_t(t[0])])
                       .cross(mesh.vertices[std::size_t(t[2])] - mesh.vertices[std::size_t(t[0])]);
    for (int c = 0; c < 3; ++c) normals[std::size_t(t[std::size_t(c)])] += n;  // area-weighted
  }
  std::vector<float> data;
  if (!flat) {
    // Smooth: one vertex per mesh vertex, drawn through the triangles' indices, so each vertex
    // is shaded once, not once per triangle (a third to a sixth of the vertex work: what limits
    // a software rasteriser on large surfaces).
    data.reserve(mesh.vertices.size() * 9);
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
      const Vec3 n = normals[v].norm() > 0 ? Vec3(normals[v].normalized()) : Vec3::Zero();
      for (int a = 0; a < 3; ++a) data.push_back(float(mesh.vertices[v][a]));
      for (int a = 0; a < 3; ++a) data.push_back(float(n[a]));
      for (int a = 0; a < 3; ++a) data.push_back(float(colour[a]));
    }
    std::vector<GLuint> indices;
    indices.reserve(mesh.triangles.size() * 3);
    for (const Tri& t : mesh.triangles)
      for (std::int32_t v : t) indices.push_back(GLuint(v));
    glBindBuffer(GL_ARRAY_BUFFER, m_vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(data.size() * sizeof(float)), data.data(), GL_DYNAMIC_DRAW);
    glBindVertexArray(m_vao);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(indices.size() * sizeof(GLuint)), indices.data(), GL_DYNAMIC_DRAW);
    glBindVertexArray(0);
    m_count = GLsizei(indices.size());
    m_indexed = true;
    return;
  }
  data.reserve(mesh.triangles.size() * 27);
  for (const Tri& t : mesh.triangles)
    for (int c = 0; c < 3; ++c) {
      const auto v = std::size_t(t[std::size_t(c)]);
      Vec3 n = normals[v].norm() > 0 ? Vec3(normals[v].normalized()) : Vec3::Zero();
      if (flat)
        n = (mesh.vertices[std::size_t(t[1])] - mesh.vertices[std::size_t(t[0])])
                .cross(mesh.vertices[std::size_t(t[2])] - mesh.vertices[std::size_t(t[0])])
                .normalized();
      for (int a = 0; a < 3; ++a) data.push_back(float(mesh.vertices[v][a]));
      for (int a = 0; a < 3; ++a) data.push_back(float(n[a]));
      for (int a = 0; a < 3; ++a) data.push_back(float(colour[a]));
    }
  glBindBuffer(GL_ARRAY_BUFFER, m_vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(data.size() * sizeof(float)), data.data(), GL_DYNAMIC_DRAW);
  m_count = GLsizei(data.size() / 9);
  m_indexed = false;
}

void MeshBuffer::upload_coloured(const geometry::TriangleMesh& mesh, const std::vector<Vec3>& vertex_colours) {
  ++g_uploads;
  std::vector<float> data;
  data.reserve(mesh.triangles.size() * 27);
  for (const Tri& t : mesh.triangles) {
    const Vec3& a = mesh.vertices[std::size_t(t[0])];
    const Vec3 n = (mesh.vertices[std::size_t(t[1])] - a).cross(mesh.vertices[std::size_t(t[2])] - a).normalized();
    for (int c = 0; c < 3; ++c) {
      const auto v = std::size_t(t[std::size_t(c)]);
      for (int k = 0; k < 3; ++k) data.push_back(float(mesh.vertices[v][k]));
      for (int k = 0; k < 3; ++k) data.push_back(float(n[k]));
      for (int k = 0; k < 3; ++k) data.push_back(float(vertex_colours[v][k]));
    }
  }
  glBindBuffer(GL_ARRAY_BUFFER, m_vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(data.size() * sizeof(float)), data.data(), GL_DYNAMIC_DRAW);
  m_count = GLsizei(data.size() / 9);
  m_indexed = false;
}

void MeshBuffer::draw() const {
  if (m_count == 0) return;
  glBindVertexArray(m_vao);
  if (m_indexed)
    glDrawElements(GL_TRIANGLES, m_count, GL_UNSIGNED_INT, nullptr);
  else
    glDrawArrays(GL_TRIANGLES, 0, m_count);
  glBindVertexArray(0);
}

LineBuffer::LineBuffer() {
  glGenVertexArrays(1, &m_vao);
  glGenBuffers(1, &m_vbo);
  glBindVertexArray(m_vao);
  glBindBuffer(GL_ARRAY_BUFFER, m_vbo);
  attribute(0, 3, 6, 0);
  attribute(1, 3, 6, 3);
  glBindVertexArray(0);
}

LineBuffer::~LineBuffer() {
  glDeleteBuffers(1, &m_vbo);
  glDeleteVertexArrays(1, &m_vao);
}

void LineBuffer::add(const Vec3& a, const Vec3& b, const Vec3& rgb) {
  for (const Vec3* p : {&a, &b}) {
    for (int c = 0; c < 3; ++c) m_data.push_back(float((*p)[c]));
    for (int c = 0; c < 3; ++c) m_data.push_back(float(rgb[c]));
  }
}

void LineBuffer::upload() {
  ++g_uploads;
  glBindBuffer(GL_ARRAY_BUFFER, m_vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(m_data.size() * sizeof(float)), m_data.data(), GL_DYNAMIC_DRAW);
  m_count = GLsizei(m_data.size() / 6);
}

void LineBuffer::draw() const {
  if (m_count == 0) return;
  glBindVertexArray(m_vao);
  glDrawArrays(GL_LINES, 0, m_count);
  glBindVertexArray(0);
}

SliceQuad::SliceQuad() {
  glGenVertexArrays(1, &m_vao);
  glGenBuffers(1, &m_vbo);
  glGenTextures(1, &m_texture);
  glBindVertexArray(m_vao);
  glBindBuffer(GL_ARRAY_BUFFER, m_vbo);
  attribute(0, 3, 5, 0);
  attribute(1, 2, 5, 3);
  glBindVertexArray(0);
  glBindTexture(GL_TEXTURE_2D, m_texture);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

SliceQuad::~SliceQuad() {
  glDeleteTextures(1, &m_texture);
  glDeleteBuffers(1, &m_vbo);
  glDeleteVertexArrays(1, &m_vao);
}

void SliceQuad::upload_image(int width, int height, const std::vector<float>& values) {
  ++g_uploads;
  glBindTexture(GL_TEXTURE_2D, m_texture);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_R32F, width, height, 0, GL_RED, GL_FLOAT, values.data());
}

void SliceQuad::set_corners(const std::array<Vec3, 4>& corners) {
  ++g_uploads;
  static constexpr float kUv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  std::vector<float> data;
  for (int i : {0, 1, 2, 0, 2, 3}) {
    for (int c = 0; c < 3; ++c) data.push_back(float(corners[std::size_t(i)][c]));
    data.push_back(kUv[i][0]);
    data.push_back(kUv[i][1]);
  }
  glBindBuffer(GL_ARRAY_BUFFER, m_vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(data.size() * sizeof(float)), data.data(), GL_DYNAMIC_DRAW);
}

void SliceQuad::draw() const {
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, m_texture);
  glBindVertexArray(m_vao);
  glDrawArrays(GL_TRIANGLES, 0, 6);
  glBindVertexArray(0);
}

Painter::Painter()
    : m_mesh(link(kMeshVs, kMeshFs)), m_lines(link(kLineVs, kLineFs)), m_slice(link(kSliceVs, kSliceFs)) {}

Painter::~Painter() {
  glDeleteProgram(m_mesh);
  glDeleteProgram(m_lines);
  glDeleteProgram(m_slice);
}

void Painter::draw_mesh(const MeshBuffer& mesh, const Mat4f& mvp, const Mat4f& view, const Eigen::Vector4f& clip,
                        bool cull_back) const {
  glUseProgram(m_mesh);
  glUniformMatrix4fv(glGetUniformLocation(m_mesh, "mvp"), 1, GL_FALSE, mvp.data());
  glUniformMatrix4fv(glGetUniformLocation(m_mesh, "view"), 1, GL_FALSE, view.data());
  glUniform4fv(glGetUniformLocation(m_mesh, "clip"), 1, clip.data());
  const bool clipped = clip != Eigen::Vector4f(0, 0, 0, 1);  // the default keeps everything: no clipping work
  if (clipped) glEnable(GL_CLIP_DISTANCE0);
  if (cull_back) {
    glFrontFace(GL_CCW);
    glCullFace(GL_BACK);
    glEnable(GL_CULL_FACE);
  }
  mesh.draw();
  if (cull_back) glDisable(GL_CULL_FACE);
  if (clipped) glDisable(GL_CLIP_DISTANCE0);
}

void Painter::draw_lines(const LineBuffer& lines, const Mat4f& mvp) const {
  glUseProgram(m_lines);
  glUniformMatrix4fv(glGetUniformLocation(m_lines, "mvp"), 1, GL_FALSE, mvp.data());
  lines.draw();
}

void Painter::draw_slice(const SliceQuad& quad, const Mat4f& mvp, double window, double level) const {
  glUseProgram(m_slice);
  glUniformMatrix4fv(glGetUniformLocation(m_slice, "mvp"), 1, GL_FALSE, mvp.data());
  glUniform1i(glGetUniformLocation(m_slice, "image"), 0);
  const double w = window > 0 ? window : 1.0;
  glUniform1f(glGetUniformLocation(m_slice, "low"), float(level - 0.5 * w));
  glUniform1f(glGetUniformLocation(m_slice, "width"), float(w));
  quad.draw();
}

std::vector<std::uint8_t> read_pixels(int width, int height) {
  std::vector<std::uint8_t> bottom_up(std::size_t(width) * std::size_t(height) * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  GLint framebuffer = 0;  // a framebuffer object (off-screen) or the window's back buffer
  glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &framebuffer);
  glReadBuffer(framebuffer != 0 ? GL_COLOR_ATTACHMENT0 : GL_BACK);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, bottom_up.data());
  std::vector<std::uint8_t> out(bottom_up.size());
  const std::size_t row = std::size_t(width) * 4;
  for (int y = 0; y < height; ++y)
    std::copy_n(bottom_up.data() + std::size_t(height - 1 - y) * row, row, out.data() + std::size_t(y) * row);
  for (std::size_t i = 3; i < out.size(); i += 4) out[i] = 255;
  return out;
}

}  // namespace ido::view::gl
