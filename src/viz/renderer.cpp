// SPDX-License-Identifier: Apache-2.0
#include "ido/viz/renderer.h"

#include <GL/osmesa.h>
#include <dlfcn.h>
#include <png.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <csetjmp>
#include <map>
#include <mutex>
#include <set>
#include <string>

#include "ido/core/atomic_file.h"
#include "ido/core/error.h"

namespace ido::viz {
namespace {

constexpr double kAmbient = 0.25;
constexpr double kDiffuse = 0.75;

std::mutex& osmesa_mutex() {
  static std::mutex m;
  return m;
}

// Mesa's OSMesa (with the LLVM it pulls in) is opened on the first render rather than linked:
// loading it at start-up cost every `ido` command about 0.1 s (relocations and page faults),
// and most commands never render. The entry points the renderer uses, resolved once.
#define IDO_OSMESA_FUNCTIONS(X)                                                                          \
  X(OSMesaCreateContextExt) X(OSMesaDestroyContext) X(OSMesaMakeCurrent) X(OSMesaPixelStore) X(glBegin) \
  X(glBindTexture) X(glClear) X(glClearColor) X(glClearDepth) X(glColor3f) X(glDeleteTextures)           \
  X(glDepthFunc) X(glDisable) X(glEnable) X(glEnd) X(glFinish) X(glGenTextures) X(glLineWidth)           \
  X(glLoadMatrixd) X(glMatrixMode) X(glPixelStorei) X(glPolygonOffset) X(glShadeModel) X(glTexCoord2f)   \
  X(glTexEnvi) X(glTexImage2D) X(glTexParameteri) X(glVertex3d) X(glVertex3f) X(glViewport)

struct OsMesaApi {
#define IDO_OSMESA_MEMBER(name) decltype(&::name) name = nullptr;
  IDO_OSMESA_FUNCTIONS(IDO_OSMESA_MEMBER)
#undef IDO_OSMESA_MEMBER
};

/// @throws ido::Error when the library or one of its entry points cannot be found.
const OsMesaApi& osmesa() {
  static const OsMesaApi api = [] {
    constexpr const char* kLibrary = "libOSMesa.so.8";
    void* lib = dlopen(kLibrary, RTLD_NOW | RTLD_LOCAL);
    if (!lib)
      throw Error(std::string("renderer: cannot load ") + kLibrary +
                  " (Mesa's off-screen OpenGL, Debian package libosmesa6): " + dlerror());
    OsMesaApi a;
#define IDO_OSMESA_LOAD(name)                                                                 \
  a.name = reinterpret_cast<decltype(&::name)>(dlsym(lib, #name));                            \
  if (!a.name) throw Error(std::string("renderer: ") + kLibrary + " has no entry point " #name);
    IDO_OSMESA_FUNCTIONS(IDO_OSMESA_LOAD)
#undef IDO_OSMESA_LOAD
    return a;
  }();
  return api;
}
#undef IDO_OSMESA_FUNCTIONS

/// PNG encoding into memory. Kept free of C++ objects with destructors between setjmp and
/// any longjmp libpng may take on error.
struct PngBuffer {
  std::vector<std::uint8_t>* out;
};

void png_write_to_vector(png_structp png, png_bytep data, png_size_t length) {
  auto* buf = static_cast<PngBuffer*>(png_get_io_ptr(png));
  buf->out->insert(buf->out->end(), data, data + length);
}
void png_flush_noop(png_structp) {}

bool encode_png(const Image& image, std::vector<std::uint8_t>& out,
                std::vector<png_bytep>& rows) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    return false;
  }
  PngBuffer buf{&out};
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, &buf, png_write_to_vector, png_flush_noop);
  png_set_IHDR(png, info, png_uint_32(image.width), png_uint_32(image.height), 8,
               PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_write_image(png, rows.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

Eigen::Vector3f to_f(const Vec3& v) { return v.cast<float>(); }

std::array<int, 2> in_slice_axes(int axis) {
  return axis == 0 ? std::array<int, 2>{1, 2}
                   : (axis == 1 ? std::array<int, 2>{0, 2} : std::array<int, 2>{0, 1});
}

void check_axis_index(const Index3& size, int axis, std::int64_t index, const char* what) {
  if (axis < 0 || axis > 2)
    throw InvalidInput(std::string(what) + ": slice axis must be 0, 1 or 2, got " +
                       std::to_string(axis));
  if (index < 0 || index >= size[std::size_t(axis)])
    throw InvalidInput(std::string(what) + ": slice index " + std::to_string(index) +
                       " outside 0.." + std::to_string(size[std::size_t(axis)] - 1));
}

}  // namespace

// ---- camera ----------------------------------------------------------------------------

Mat4 Camera::view_matrix() const {
  const Vec3 z = direction.normalized();
  Vec3 x = up.cross(z);
  if (x.norm() < 1e-12) x = z.unitOrthogonal();
  x.normalize();
  const Vec3 y = z.cross(x);
  const Vec3 e = eye();
  Mat4 m = Mat4::Identity();
  m.block<1, 3>(0, 0) = x.transpose();
  m.block<1, 3>(1, 0) = y.transpose();
  m.block<1, 3>(2, 0) = z.transpose();
  m(0, 3) = -x.dot(e);
  m(1, 3) = -y.dot(e);
  m(2, 3) = -z.dot(e);
  return m;
}

Mat4 Camera::projection_matrix(double aspect) const {
  const double n = near_mm, f = far_mm;
  Mat4 p = Mat4::Zero();
  if (projection == Projection::Orthographic) {
    const double t = half_height_mm, r = half_height_mm * aspect;
    p(0, 0) = 1.0 / r;
    p(1, 1) = 1.0 / t;
    p(2, 2) = -2.0 / (f - n);
    p(2, 3) = -(f + n) / (f - n);
    p(3, 3) = 1.0;
  } else {
    const double t = 1.0 / std::tan(0.5 * fov_y_deg * kPi / 180.0);
    p(0, 0) = t / aspect;
    p(1, 1) = t;
    p(2, 2) = -(f + n) / (f - n);
    p(2, 3) = -2.0 * f * n / (f - n);
    p(3, 2) = -1.0;
  }
  return p;
}

Camera Camera::orbit(const Vec3& lo, const Vec3& hi, double azimuth_deg, double elevation_deg,
                     Projection projection, double aspect) {
  Camera c;
  c.projection = projection;
  c.target = 0.5 * (lo + hi);
  const double radius = std::max(0.5 * (hi - lo).norm(), 1e-3);
  const double az = azimuth_deg * kPi / 180.0, el = elevation_deg * kPi / 180.0;
  c.direction = Vec3(std::cos(el) * std::sin(az), -std::cos(el) * std::cos(az), std::sin(el));
  c.up = std::abs(std::cos(el)) < 1e-6 ? Vec3(-std::sin(az), std::cos(az), 0.0) * (el > 0 ? 1 : -1)
                                       : Vec3(0, 0, 1);
  const double margin = 1.05;
  const double fit = aspect >= 1.0 ? 1.0 : 1.0 / aspect;  // the narrower side must hold it
  c.half_height_mm = radius * margin * fit;
  c.distance_mm = projection == Projection::Orthographic
                      ? 3.0 * radius
                      : radius * margin * fit / std::sin(0.5 * c.fov_y_deg * kPi / 180.0);
  c.near_mm = std::max(1e-3, c.distance_mm - 1.5 * radius);
  c.far_mm = c.distance_mm + 1.5 * radius;
  return c;
}

// ---- colour maps -------------------------------------------------------------------------

Vec3 colormap_rgb(Colormap map, double t) {
  // Control points sampled from the published maps; linear in between.
  static const std::array<std::array<double, 4>, 10> viridis = {{
      {0.0, 0.267004, 0.004874, 0.329415},
      {0.125, 0.282623, 0.140926, 0.457517},
      {0.25, 0.253935, 0.265254, 0.529983},
      {0.375, 0.206756, 0.371758, 0.553117},
      {0.5, 0.163625, 0.471133, 0.558148},
      {0.625, 0.127568, 0.566949, 0.550556},
      {0.75, 0.134692, 0.658636, 0.517649},
      {0.875, 0.266941, 0.748751, 0.440573},
      {0.9375, 0.555, 0.815, 0.275},
      {1.0, 0.993248, 0.906157, 0.143936},
  }};
  static const std::array<std::array<double, 4>, 5> coolwarm = {{
      {0.0, 0.230, 0.299, 0.754},
      {0.25, 0.552, 0.690, 0.996},
      {0.5, 0.865, 0.865, 0.865},
      {0.75, 0.958, 0.603, 0.482},
      {1.0, 0.706, 0.016, 0.150},
  }};
  if (!std::isfinite(t)) t = 0;
  t = std::clamp(t, 0.0, 1.0);
  auto lerp = [&](const auto& table) {
    for (std::size_t i = 1; i < table.size(); ++i) {
      if (t <= table[i][0]) {
        const auto& a = table[i - 1];
        const auto& b = table[i];
        const double w = (t - a[0]) / (b[0] - a[0]);
        return Vec3(a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2]), a[3] + w * (b[3] - a[3]));
      }
    }
    const auto& l = table.back();
    return Vec3(l[1], l[2], l[3]);
  };
  return map == Colormap::Viridis ? lerp(viridis) : lerp(coolwarm);
}

// ---- PNG -----------------------------------------------------------------------------------

void write_png(const std::filesystem::path& path, const Image& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgba.size() != std::size_t(image.width) * std::size_t(image.height) * 4)
    throw InvalidInput("write_png: image buffer does not match its " +
                       std::to_string(image.width) + "x" + std::to_string(image.height) + " size");
  std::vector<png_bytep> rows(std::size_t(image.height));
  for (int y = 0; y < image.height; ++y)
    rows[std::size_t(y)] = const_cast<png_bytep>(image.pixel(0, y));
  std::vector<std::uint8_t> encoded;
  if (!encode_png(image, encoded, rows)) throw IoError(path, "PNG encoding failed");
  write_file_atomically(path, [&](std::ostream& os) {
    os.write(reinterpret_cast<const char*>(encoded.data()), std::streamsize(encoded.size()));
  });
}

// ---- renderer --------------------------------------------------------------------------

Renderer::Renderer(int width, int height) : m_width(width), m_height(height) {
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw InvalidInput("renderer: picture size must be within 1..16384 pixels, got " +
                       std::to_string(width) + "x" + std::to_string(height));
}

void Renderer::grow_bounds(const Vec3& p) { m_bounds.extend(p); }

geometry::Aabb Renderer::bounds() const {
  if (m_bounds.empty()) return {Vec3::Zero(), Vec3::Zero()};
  return m_bounds;
}

void Renderer::add_surface(const geometry::TriangleMesh& mesh, const Vec3& colour_rgb,
                           const SurfaceOptions& options) {
  const auto nv = mesh.vertices.size();
  for (const Tri& t : mesh.triangles)
    for (auto i : t)
      if (i < 0 || std::size_t(i) >= nv)
        throw InvalidInput("renderer: triangle index " + std::to_string(i) + " out of range");
  std::vector<Vec3> vn;
  if (options.shading == Shading::Smooth) {
    vn.assign(nv, Vec3::Zero());
    for (const Tri& t : mesh.triangles) {
      const Vec3 n = (mesh.vertices[std::size_t(t[1])] - mesh.vertices[std::size_t(t[0])])
                         .cross(mesh.vertices[std::size_t(t[2])] - mesh.vertices[std::size_t(t[0])]);
      for (auto i : t) vn[std::size_t(i)] += n;  // area weighted
    }
    for (auto& n : vn) n.normalize();
  }
  const Eigen::Vector3f c = to_f(colour_rgb.cwiseMax(0.0).cwiseMin(1.0));
  for (const Tri& t : mesh.triangles) {
    const Vec3 fn = (mesh.vertices[std::size_t(t[1])] - mesh.vertices[std::size_t(t[0])])
                        .cross(mesh.vertices[std::size_t(t[2])] - mesh.vertices[std::size_t(t[0])])
                        .normalized();
    for (auto i : t) {
      const Vec3& p = mesh.vertices[std::size_t(i)];
      grow_bounds(p);
      const Vec3 n = options.shading == Shading::Smooth ? vn[std::size_t(i)] : fn;
      m_triangles.push_back({to_f(p), to_f(n.allFinite() ? n : Vec3::Zero()), c});
    }
    m_two_sided.push_back(options.two_sided);
  }
}

void Renderer::add_tet_mesh_clipped(const geometry::TetMesh& mesh, const ClipPlane& plane,
                                    const std::string& cell_field, const TetClipOptions& options) {
  const auto nv = mesh.vertices.size();
  for (const Tet& t : mesh.tets)
    for (auto i : t)
      if (i < 0 || std::size_t(i) >= nv)
        throw InvalidInput("renderer: tetrahedron index " + std::to_string(i) + " out of range");
  const geometry::Field* field = nullptr;
  if (!cell_field.empty()) {
    auto it = mesh.cell_fields.find(cell_field);
    if (it == mesh.cell_fields.end()) {
      std::string names;
      for (const auto& [name, f] : mesh.cell_fields) names += (names.empty() ? "" : ", ") + name;
      throw InvalidInput("renderer: the tetrahedral mesh has no cell field '" + cell_field +
                         "' (it has: " + (names.empty() ? "none" : names) + ")");
    }
    field = &it->second;
    if (field->components < 1 || field->count() != mesh.tets.size())
      throw InvalidInput("renderer: cell field '" + cell_field + "' has " +
                         std::to_string(field->count()) + " entries for " +
                         std::to_string(mesh.tets.size()) + " tetrahedra");
  }
  const Vec3 normal = plane.normal.normalized();
  std::vector<char> keep(mesh.tets.size(), 0);
  double lo = INFINITY, hi = -INFINITY;
  for (std::size_t i = 0; i < mesh.tets.size(); ++i) {
    Vec3 c = Vec3::Zero();
    for (auto v : mesh.tets[i]) c += 0.25 * mesh.vertices[std::size_t(v)];
    keep[i] = (c - plane.point).dot(normal) <= 0.0;
    if (field) {
      const double x = field->values[i * std::size_t(field->components)];
      if (std::isfinite(x)) {
        lo = std::min(lo, x);
        hi = std::max(hi, x);
      }
    }
  }
  if (options.range_min) lo = *options.range_min;
  if (options.range_max) hi = *options.range_max;
  // boundary faces of the kept set: faces seen once
  std::map<std::array<std::int32_t, 3>, std::pair<int, std::pair<std::size_t, Tri>>> faces;
  for (std::size_t i = 0; i < mesh.tets.size(); ++i) {
    if (!keep[i]) continue;
    const Tet& t = mesh.tets[i];
    const std::array<Tri, 4> f = {{{t[1], t[2], t[3]}, {t[0], t[3], t[2]}, {t[0], t[1], t[3]},
                                   {t[0], t[2], t[1]}}};
    for (const Tri& tri : f) {
      std::array<std::int32_t, 3> key = tri;
      std::sort(key.begin(), key.end());
      auto& e = faces[key];
      ++e.first;
      e.second = {i, tri};
    }
  }
  std::set<std::pair<std::int32_t, std::int32_t>> edges;  // of the drawn faces, each once
  for (const auto& [key, e] : faces) {
    if (e.first != 1) continue;
    const auto [tet, tri] = e.second;
    if (options.edges)
      for (int k = 0; k < 3; ++k) edges.insert(std::minmax(tri[std::size_t(k)], tri[std::size_t((k + 1) % 3)]));
    Vec3 colour = options.uniform_colour;
    if (field) {
      const double x = field->values[tet * std::size_t(field->components)];
      const double t = hi > lo ? (x - lo) / (hi - lo) : 0.5;
      colour = colormap_rgb(options.colormap, t);
    }
    const Vec3& a = mesh.vertices[std::size_t(tri[0])];
    const Vec3& b = mesh.vertices[std::size_t(tri[1])];
    const Vec3& c = mesh.vertices[std::size_t(tri[2])];
    const Vec3 n = (b - a).cross(c - a).normalized();
    for (const Vec3* p : {&a, &b, &c}) {
      grow_bounds(*p);
      m_triangles.push_back({to_f(*p), to_f(n.allFinite() ? n : Vec3::Zero()), to_f(colour)});
    }
    m_two_sided.push_back(true);
  }
  for (const auto& [a, b] : edges)
    m_lines.push_back({to_f(mesh.vertices[std::size_t(a)]), to_f(mesh.vertices[std::size_t(b)]),
                       to_f(options.edge_colour)});
}

void Renderer::add_slice(const image::Volume<float>& volume, int axis, std::int64_t index,
                         const SliceOptions& options) {
  if (volume.empty()) throw InvalidInput("renderer: the slice's volume is empty");
  check_axis_index(volume.size(), axis, index, "renderer");
  const auto [ua, va] = in_slice_axes(axis);
  Slice s;
  s.grid = image::Volume<float>({1, 1, 1}, volume.spacing(), volume.origin(), volume.direction());
  s.grid_size = volume.size();
  s.axis = axis;
  s.index = index;
  s.tex_w = int(volume.size(ua));
  s.tex_h = int(volume.size(va));
  auto voxel = [&](std::int64_t u, std::int64_t v) {
    std::int64_t ijk[3];
    ijk[axis] = index;
    ijk[ua] = u;
    ijk[va] = v;
    return volume(ijk[0], ijk[1], ijk[2]);
  };
  double lo = options.level - 0.5 * options.window, width = options.window;
  if (!(options.window > 0)) {
    double mn = INFINITY, mx = -INFINITY;
    for (int v = 0; v < s.tex_h; ++v)
      for (int u = 0; u < s.tex_w; ++u) {
        const double x = voxel(u, v);
        if (std::isfinite(x)) {
          mn = std::min(mn, x);
          mx = std::max(mx, x);
        }
      }
    lo = std::isfinite(mn) ? mn : 0.0;
    width = (std::isfinite(mx) && mx > mn) ? mx - mn : 1.0;
  }
  s.texels.resize(std::size_t(s.tex_w) * std::size_t(s.tex_h) * 3);
  for (int v = 0; v < s.tex_h; ++v)
    for (int u = 0; u < s.tex_w; ++u) {
      double g = (double(voxel(u, v)) - lo) / width;
      if (!std::isfinite(g)) g = 0;
      const auto byte = std::uint8_t(std::lround(std::clamp(g, 0.0, 1.0) * 255.0));
      for (int c = 0; c < 3; ++c)
        s.texels[(std::size_t(v) * std::size_t(s.tex_w) + std::size_t(u)) * 3 + std::size_t(c)] = byte;
    }
  auto corner = [&](double u, double v) {
    Vec3 idx;
    idx[axis] = double(index);
    idx[ua] = u;
    idx[va] = v;
    return volume.index_to_world(idx);
  };
  const double u1 = double(s.tex_w) - 0.5, v1 = double(s.tex_h) - 0.5;
  s.corners = {corner(-0.5, -0.5), corner(u1, -0.5), corner(u1, v1), corner(-0.5, v1)};
  for (const Vec3& c : s.corners) grow_bounds(c);
  m_slices.push_back(std::move(s));
}

void Renderer::add_contour(const image::Volume<std::uint8_t>& mask, int axis, std::int64_t index,
                           const Vec3& colour_rgb) {
  if (mask.empty()) throw InvalidInput("renderer: the contour's mask is empty");
  check_axis_index(mask.size(), axis, index, "renderer contour");
  const auto [ua, va] = in_slice_axes(axis);
  bool matched = false;
  std::array<std::uint8_t, 3> rgb{};
  for (int c = 0; c < 3; ++c)
    rgb[std::size_t(c)] = std::uint8_t(std::lround(std::clamp(colour_rgb[c], 0.0, 1.0) * 255.0));
  auto in = [&](std::int64_t u, std::int64_t v) {
    if (u < 0 || v < 0 || u >= mask.size(ua) || v >= mask.size(va)) return false;
    std::int64_t ijk[3];
    ijk[axis] = index;
    ijk[ua] = u;
    ijk[va] = v;
    return mask(ijk[0], ijk[1], ijk[2]) != 0;
  };
  for (Slice& s : m_slices) {
    if (s.axis != axis || s.index != index || s.grid_size != mask.size()) continue;
    image::Volume<std::uint8_t> probe({1, 1, 1}, mask.spacing(), mask.origin(), mask.direction());
    if (!s.grid.same_grid(probe)) continue;
    matched = true;
    for (int v = 0; v < s.tex_h; ++v)
      for (int u = 0; u < s.tex_w; ++u) {
        if (!in(u, v)) continue;
        if (in(u - 1, v) && in(u + 1, v) && in(u, v - 1) && in(u, v + 1)) continue;
        std::uint8_t* t = &s.texels[(std::size_t(v) * std::size_t(s.tex_w) + std::size_t(u)) * 3];
        t[0] = rgb[0];
        t[1] = rgb[1];
        t[2] = rgb[2];
      }
  }
  if (!matched)
    throw InvalidInput("renderer: no slice on the mask's grid at axis " + std::to_string(axis) +
                       ", index " + std::to_string(index) + " to draw the contour on");
}

Camera Renderer::fit_camera(double azimuth_deg, double elevation_deg, Projection projection) const {
  const auto [lo, hi] = bounds();
  return Camera::orbit(lo, hi, azimuth_deg, elevation_deg, projection,
                       double(m_width) / double(m_height));
}

Camera Renderer::slice_camera(std::size_t slice) const {
  if (slice >= m_slices.size())
    throw InvalidInput("renderer: no slice number " + std::to_string(slice) + " to look at");
  const Slice& s = m_slices[slice];
  const Vec3 right = s.corners[1] - s.corners[0];  // +u
  const Vec3 down = s.corners[3] - s.corners[0];   // +v
  Camera c;
  c.projection = Projection::Orthographic;
  c.target = 0.25 * (s.corners[0] + s.corners[1] + s.corners[2] + s.corners[3]);
  c.up = -down.normalized();
  c.direction = right.normalized().cross(c.up).normalized();
  const double aspect = double(m_width) / double(m_height);
  c.half_height_mm = std::max(0.5 * down.norm(), 0.5 * right.norm() / aspect);
  const auto [lo, hi] = bounds();
  const double radius = std::max(0.5 * (hi - lo).norm(), 1.0);
  c.distance_mm = 3.0 * radius;
  c.near_mm = radius;
  c.far_mm = 5.0 * radius;
  return c;
}

Image Renderer::render() const {
  const Camera cam = m_camera ? *m_camera : fit_camera(30.0, 20.0, Projection::Perspective);
  const double aspect = double(m_width) / double(m_height);
  const Mat4 view = cam.view_matrix();
  const Mat4 proj = cam.projection_matrix(aspect);
  const Vec3 eye = cam.eye();
  const Vec3 towards_eye = cam.direction.normalized();

  Image image;
  image.width = m_width;
  image.height = m_height;
  image.rgba.assign(std::size_t(m_width) * std::size_t(m_height) * 4, 0);

  const OsMesaApi& gl = osmesa();
  std::lock_guard<std::mutex> lock(osmesa_mutex());
  OSMesaContext ctx = gl.OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
  if (!ctx) throw Error("renderer: OSMesa could not create an off-screen OpenGL context");
  struct ContextGuard {
    OSMesaContext c;
    ~ContextGuard() { osmesa().OSMesaDestroyContext(c); }
  } guard{ctx};
  if (!gl.OSMesaMakeCurrent(ctx, image.rgba.data(), GL_UNSIGNED_BYTE, m_width, m_height))
    throw Error("renderer: OSMesa could not bind the picture buffer");
  gl.OSMesaPixelStore(OSMESA_Y_UP, 0);  // first row of the buffer = top of the picture

  gl.glViewport(0, 0, m_width, m_height);
  gl.glClearColor(float(m_background[0]), float(m_background[1]), float(m_background[2]), 1.0f);
  gl.glClearDepth(1.0);
  gl.glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  gl.glEnable(GL_DEPTH_TEST);
  gl.glDepthFunc(GL_LEQUAL);
  gl.glDisable(GL_LIGHTING);
  gl.glDisable(GL_CULL_FACE);
  gl.glShadeModel(GL_SMOOTH);
  gl.glMatrixMode(GL_PROJECTION);
  gl.glLoadMatrixd(proj.data());
  gl.glMatrixMode(GL_MODELVIEW);
  gl.glLoadMatrixd(view.data());

  // Triangles, lit on the CPU by a headlight: ambient + diffuse · |n · l| (two-sided) or
  // max(0, n · l) (one-sided), l pointing from the surface to the eye.
  // Faces are pushed slightly back so that edge lines drawn on them win the depth test.
  if (!m_lines.empty()) {
    gl.glEnable(GL_POLYGON_OFFSET_FILL);
    gl.glPolygonOffset(1.0f, 1.0f);
  }
  gl.glBegin(GL_TRIANGLES);
  for (std::size_t t = 0; t < m_two_sided.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const Vertex& v = m_triangles[3 * t + std::size_t(k)];
      const Vec3 p = v.position.cast<double>();
      const Vec3 l = cam.projection == Projection::Perspective ? (eye - p).normalized() : towards_eye;
      const double nl = v.normal.cast<double>().dot(l);
      const double lambert = m_two_sided[t] ? std::abs(nl) : std::max(0.0, nl);
      const double shade = kAmbient + kDiffuse * lambert;
      const Eigen::Vector3f c = (v.colour * float(shade)).cwiseMin(1.0f);
      gl.glColor3f(c[0], c[1], c[2]);
      gl.glVertex3f(v.position[0], v.position[1], v.position[2]);
    }
  }
  gl.glEnd();
  if (!m_lines.empty()) {
    gl.glDisable(GL_POLYGON_OFFSET_FILL);
    gl.glLineWidth(1.0f);
    gl.glBegin(GL_LINES);
    for (const auto& line : m_lines) {
      gl.glColor3f(line[2][0], line[2][1], line[2][2]);
      gl.glVertex3f(line[0][0], line[0][1], line[0][2]);
      gl.glVertex3f(line[1][0], line[1][1], line[1][2]);
    }
    gl.glEnd();
  }

  // Slices: unlit textured quads, one texel per voxel.
  if (!m_slices.empty()) {
    gl.glEnable(GL_TEXTURE_2D);
    gl.glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    gl.glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_REPLACE);
    for (const Slice& s : m_slices) {
      GLuint tex = 0;
      gl.glGenTextures(1, &tex);
      gl.glBindTexture(GL_TEXTURE_2D, tex);
      gl.glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      gl.glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      gl.glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
      gl.glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
      gl.glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, s.tex_w, s.tex_h, 0, GL_RGB, GL_UNSIGNED_BYTE,
                   s.texels.data());
      const float tc[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      gl.glBegin(GL_QUADS);
      for (int k = 0; k < 4; ++k) {
        gl.glTexCoord2f(tc[k][0], tc[k][1]);
        const Vec3& p = s.corners[std::size_t(k)];
        gl.glVertex3d(p[0], p[1], p[2]);
      }
      gl.glEnd();
      gl.glDeleteTextures(1, &tex);
    }
    gl.glDisable(GL_TEXTURE_2D);
  }
  gl.glFinish();
  return image;
}

void Renderer::write_png(const std::filesystem::path& path) const {
  viz::write_png(path, render());
}

}  // namespace ido::viz
