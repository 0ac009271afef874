// SPDX-License-Identifier: Apache-2.0
#include "ido/viz/renderer.h"


#include <cmath>
#include <cstdio>
#include <set>
#include <utility>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/geometry/primitives.h"
#include "support/png_read.h"
#include "support/test_support.h"

namespace ido::viz {
namespace {

bool is_background(const Image& im, int x, int y) {
  const auto* p = im.pixel(x, y);
  return p[0] == 255 && p[1] == 255 && p[2] == 255;
}

// Orthographic camera at target + distance · direction looking at @p target.
Camera ortho(const Vec3& target, const Vec3& direction, const Vec3& up, double half_height_mm,
             double distance_mm, double near_mm) {
  Camera c;
  c.projection = Projection::Orthographic;
  c.target = target;
  c.direction = direction;
  c.up = up;
  c.distance_mm = distance_mm;
  c.near_mm = near_mm;
  c.far_mm = 200;
  c.half_height_mm = half_height_mm;
  return c;
}

// Looking along +y at the origin (from −y), z up in the picture.
Camera front_ortho(double half_height_mm) {
  return ortho(Vec3::Zero(), Vec3(0, -1, 0), Vec3(0, 0, 1), half_height_mm, 100, 10);
}

// Looking down −z at @p target from above, y up in the picture.
Camera top_ortho(const Vec3& target, double half_height_mm) {
  return ortho(target, Vec3(0, 0, 1), Vec3(0, 1, 0), half_height_mm, 50, 1);
}

TEST(Renderer, SphereSilhouetteCoversPiRSquaredPixels) {
  const double r = 10.0;
  Renderer ren(200, 200);
  ren.add_surface(geometry::icosphere(Vec3::Zero(), r, 5), Vec3(0.2, 0.5, 0.9));
  ren.set_camera(front_ortho(20.0));  // 200 px over 40 mm: 5 px per mm
  const Image im = ren.render();
  ASSERT_EQ(im.rgba.size(), 200u * 200u * 4u);
  int covered = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) covered += is_background(im, x, y) ? 0 : 1;
  const double expected = kPi * (r * 5) * (r * 5);
  EXPECT_TRUE(test::rel_near(covered, expected, 0.02));
}

TEST(Renderer, HeadlightMakesTheSphereBrightestAtItsCentre) {
  const double r = 10.0;
  Renderer ren(201, 201);
  ren.add_surface(geometry::icosphere(Vec3::Zero(), r, 5), Vec3(1, 0, 0));
  Camera cam = front_ortho(20.1);  // 201 px over 40.2 mm: 5 px per mm, centre pixel 100
  ren.set_camera(cam);
  const Image im = ren.render();
  int best = -1;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x)
      if (!is_background(im, x, y)) best = std::max(best, int(im.pixel(x, y)[0]));
  // every pixel at the brightest value lies at the centre (within 0.3 r = 15 px); the
  // centre pixel is within one level of it
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      if (!is_background(im, x, y) && im.pixel(x, y)[0] == best) {
        EXPECT_LE(std::hypot(x - 100, y - 100), 15.0) << x << "," << y;
      }
    }
  EXPECT_GE(int(im.pixel(100, 100)[0]), best - 1);
  // Lambert under a headlight: 0.25 + 0.75 cos θ with sin θ = ρ / r
  for (double rho_mm : {0.0, 3.0, 6.0, 8.0, 9.5}) {
    const int x = 100 + int(std::lround(rho_mm * 5));
    const double expected = 255.0 * (0.25 + 0.75 * std::sqrt(1 - (rho_mm / r) * (rho_mm / r)));
    EXPECT_TRUE(test::near(im.pixel(x, 100)[0], expected, 0.03 * 255)) << "at " << rho_mm << " mm";
  }
  // brightness falls monotonically along a radius
  int previous = 256;
  for (int x = 100; x < 100 + 48; x += 4) {
    EXPECT_LE(int(im.pixel(x, 100)[0]), previous);
    previous = im.pixel(x, 100)[0];
  }
}

TEST(Renderer, PerspectiveFitCentresTheScene) {
  Renderer ren(160, 120);
  ren.add_surface(geometry::icosphere(Vec3(5, -3, 2), 4.0, 3), Vec3(0.8, 0.3, 0.3),
                  {.shading = Shading::Flat});
  ren.set_camera(ren.fit_camera(40, 25, Projection::Perspective));
  const Image im = ren.render();
  double sx = 0, sy = 0, n = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x)
      if (!is_background(im, x, y)) {
        sx += x + 0.5;
        sy += y + 0.5;
        ++n;
      }
  ASSERT_GT(n, 100);
  EXPECT_TRUE(test::near(sx / n, 80.0, 1.0));
  EXPECT_TRUE(test::near(sy / n, 60.0, 1.0));
  // the fitted sphere lies wholly inside the picture
  for (int x = 0; x < im.width; ++x) {
    EXPECT_TRUE(is_background(im, x, 0));
    EXPECT_TRUE(is_background(im, x, im.height - 1));
  }
}

/// The in-slice contour of a mask computed here independently: (u, v) pixels.
std::set<std::pair<int, int>> truth_contour(const image::Volume<std::uint8_t>& m, int axis,
                                            std::int64_t index) {
  const int ua = axis == 0 ? 1 : 0, va = axis == 2 ? 1 : 2;
  auto at = [&](std::int64_t u, std::int64_t v) {
    if (u < 0 || v < 0 || u >= m.size(ua) || v >= m.size(va)) return false;
    Vec3i ijk;
    ijk[axis] = int(index);
    ijk[ua] = int(u);
    ijk[va] = int(v);
    return m(ijk[0], ijk[1], ijk[2]) != 0;
  };
  std::set<std::pair<int, int>> out;
  for (std::int64_t v = 0; v < m.size(va); ++v)
    for (std::int64_t u = 0; u < m.size(ua); ++u)
      if (at(u, v) && !(at(u - 1, v) && at(u + 1, v) && at(u, v - 1) && at(u, v + 1)))
        out.insert({int(u), int(v)});
  return out;
}

void check_slice_overlay(int axis) {
  // a CT-like volume and an irregular mask (a blob with a notch and a hole, touching a side)
  image::Volume<float> ct({50, 40, 30}, Vec3::Constant(0.8), Vec3(-20, 5, 30));
  auto mask = ct.like<std::uint8_t>();
  for (std::int64_t k = 0; k < 30; ++k)
    for (std::int64_t j = 0; j < 40; ++j)
      for (std::int64_t i = 0; i < 50; ++i) {
        const double x = double(i) - 22, y = double(j) - 18, z = double(k) - 14;
        const bool blob = x * x / 200 + y * y / 120 + z * z / 90 < 1 && !(x > 5 && std::abs(y) < 3);
        const bool hole = x * x + (y - 4) * (y - 4) + z * z < 9;
        const bool side = i < 3 && std::abs(y) < 5;
        mask(i, j, k) = (blob && !hole) || side ? 1 : 0;
        ct(i, j, k) = float(mask(i, j, k) ? 300 + 20 * std::sin(double(i + j)) : -100 + 3 * double(k));
      }
  const std::int64_t index = 14;
  const int ua = axis == 0 ? 1 : 0, va = axis == 2 ? 1 : 2;
  const int w = int(ct.size(ua)), h = int(ct.size(va));
  Renderer ren(w, h);
  ren.add_slice(ct, axis, index, {.window = 800, .level = 100});
  ren.add_contour(mask, axis, index, Vec3(1, 0, 0));
  ren.set_camera(ren.slice_camera());
  const Image im = ren.render();
  const auto truth = truth_contour(mask, axis, index);
  ASSERT_GT(truth.size(), 20u);
  std::set<std::pair<int, int>> marked;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const auto* p = im.pixel(x, y);
      if (p[0] == 255 && p[1] == 0 && p[2] == 0) marked.insert({x, y});
      else EXPECT_TRUE(p[0] == p[1] && p[1] == p[2]) << "grey CT pixel at " << x << "," << y;
    }
  EXPECT_EQ(marked, truth);
}

TEST(Renderer, SliceOverlayMarksExactlyTheTruthContourAxial) { check_slice_overlay(2); }
TEST(Renderer, SliceOverlayMarksExactlyTheTruthContourCoronal) { check_slice_overlay(1); }
TEST(Renderer, SliceOverlayMarksExactlyTheTruthContourSagittal) { check_slice_overlay(0); }

TEST(Renderer, SliceWindowMapsValuesToGrey) {
  image::Volume<float> v({4, 3, 2}, Vec3::Constant(1.0));
  for (std::int64_t i = 0; i < 4; ++i)
    for (std::int64_t j = 0; j < 3; ++j) v(i, j, 1) = float(-100 + 100 * i);  // -100..200
  Renderer ren(4, 3);
  ren.add_slice(v, 2, 1, {.window = 200, .level = 0});  // -100 → 0, 100 → 255
  ren.set_camera(ren.slice_camera());
  const Image im = ren.render();
  EXPECT_EQ(im.pixel(0, 0)[0], 0);
  EXPECT_EQ(im.pixel(1, 1)[0], 128);
  EXPECT_EQ(im.pixel(2, 2)[0], 255);
  EXPECT_EQ(im.pixel(3, 0)[0], 255);
}

/// Inverse of the colour map by the nearest of 1024 samples; also returns the RGB distance.
std::pair<double, double> invert(Colormap map, const std::uint8_t* p) {
  double best = INFINITY, bt = 0;
  for (int i = 0; i <= 1023; ++i) {
    const Vec3 c = 255.0 * colormap_rgb(map, i / 1023.0);
    const double d = (c - Vec3(p[0], p[1], p[2])).norm();
    if (d < best) {
      best = d;
      bt = i / 1023.0;
    }
  }
  return {bt, best};
}

TEST(Renderer, ClippedTetMeshShowsAMonotoneRampOfALinearField) {
  auto mesh = geometry::box_tets(Vec3(0, 0, 0), Vec3(40, 20, 20), 8);
  geometry::Field x;
  for (const Tet& t : mesh.tets) {
    double cx = 0;
    for (auto v : t) cx += 0.25 * mesh.vertices[std::size_t(v)].x();
    x.values.push_back(cx);
  }
  mesh.cell_fields["x_mm"] = x;
  for (Colormap map : {Colormap::Viridis, Colormap::CoolWarm}) {
    Renderer ren(200, 100);
    // keep z ≤ 10 (a plane between tetrahedron layers) and look down on the cut
    TetClipOptions options;
    options.colormap = map;
    ren.add_tet_mesh_clipped(mesh, {.point = Vec3(0, 0, 10), .normal = Vec3(0, 0, 1)}, "x_mm",
                             options);
    ren.set_camera(top_ortho(Vec3(20, 10, 10), 10));  // 100 px over 20 mm; 200 px over 40 mm
    const Image im = ren.render();
    double previous = -1, first = -1, last = -1;
    for (int px = 2; px < 198; ++px) {
      const auto [t, err] = invert(map, im.pixel(px, 50));
      EXPECT_LT(err, 4.0) << "a face seen head-on shows exactly its colour map colour";
      EXPECT_GE(t, previous - 1e-9) << "at pixel " << px;
      previous = t;
      if (first < 0) first = t;
      last = t;
    }
    EXPECT_LT(first, 0.1);
    EXPECT_GT(last, 0.9);
  }
}

TEST(Renderer, ClipRemovesTheFarSide) {
  auto mesh = geometry::box_tets(Vec3(0, 0, 0), Vec3(10, 10, 10), 4);
  Renderer ren(100, 100);
  ren.add_tet_mesh_clipped(mesh, {.point = Vec3(5, 0, 0), .normal = Vec3(1, 0, 0)}, "");
  const auto [lo, hi] = ren.bounds();
  EXPECT_TRUE(test::near(hi.x(), 5.0, 1e-12));
  EXPECT_TRUE(test::near(lo.x(), 0.0, 1e-12));
}

// Edges drawn on a clipped mesh: looking straight at the cut face of a cube of 4 × 4 × 4
// cells, every cell boundary line of the face carries edge pixels, and without the option
// no pixel has the edge colour.
TEST(Renderer, ClippedTetMeshEdgesMarkTheCellBoundaries) {
  const auto mesh = geometry::box_tets(Vec3(0, 0, 0), Vec3(10, 10, 10), 4);
  auto picture = [&](bool edges) {
    Renderer ren(100, 100);
    TetClipOptions options;
    options.edges = edges;
    options.edge_colour = Vec3(1, 0, 0);
    options.uniform_colour = Vec3(0.5, 0.5, 0.5);
    ren.add_tet_mesh_clipped(mesh, {.point = Vec3(0, 0, 5), .normal = Vec3(0, 0, 1)}, "", options);
    ren.set_camera(top_ortho(Vec3(5, 5, 5), 5));  // 10 px per mm: cell boundaries at columns 25, 50, 75
    return ren.render();
  };
  auto red = [](const Image& im, int x, int y) {
    const auto* p = im.pixel(x, y);
    return p[0] > 200 && p[1] < 60 && p[2] < 60;
  };
  const Image plain = picture(false), lined = picture(true);
  int red_plain = 0, red_lined = 0;
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 100; ++x) {
      red_plain += red(plain, x, y);
      red_lined += red(lined, x, y);
    }
  EXPECT_EQ(red_plain, 0);
  EXPECT_LT(red_lined, 100 * 100 / 3) << "the faces stay visible between the edges";
  for (int column : {25, 50, 75}) {
    int hits = 0;
    for (int y = 5; y < 95; ++y) hits += red(lined, column - 1, y) || red(lined, column, y);
    EXPECT_GE(hits, 85) << "cell boundary at column " << column;
  }
  // A column in the middle of a cell meets only the diagonal edges of the cut face.
  int middle = 0;
  for (int y = 5; y < 95; ++y) middle += red(lined, 12, y);
  EXPECT_LT(middle, 30);
}

TEST(Renderer, PngRoundTrip) {
  Renderer ren(64, 48);
  ren.add_surface(geometry::icosphere(Vec3::Zero(), 3, 2), Vec3(0.9, 0.6, 0.1));
  const Image im = ren.render();
  const auto path = test::scratch_dir("viz_png") / "sphere.png";
  write_png(path, im);
  const test::Png back = test::read_png(path);
  EXPECT_EQ(back.w, 64);
  EXPECT_EQ(back.h, 48);
  EXPECT_EQ(back.rgba, im.rgba);
}

TEST(Renderer, BadInputThrows) {
  EXPECT_THROW(Renderer(0, 10), InvalidInput);
  EXPECT_THROW(Renderer(10, 100000), InvalidInput);
  Renderer ren(10, 10);
  geometry::TriangleMesh bad;
  bad.vertices = {Vec3::Zero()};
  bad.triangles = {{0, 1, 2}};
  EXPECT_THROW(ren.add_surface(bad, Vec3::Ones()), InvalidInput);
  const auto tets = geometry::box_tets(Vec3::Zero(), Vec3::Ones(), 1);
  EXPECT_THROW(ren.add_tet_mesh_clipped(tets, {}, "no_such_field"), InvalidInput);
  image::Volume<float> v({4, 4, 4});
  EXPECT_THROW(ren.add_slice(v, 3, 0), InvalidInput);
  EXPECT_THROW(ren.add_slice(v, 2, 4), InvalidInput);
  EXPECT_THROW(ren.add_contour(v.like<std::uint8_t>(), 2, 1), InvalidInput);  // no slice
  EXPECT_THROW((void)ren.slice_camera(), InvalidInput);
  Image broken{.width = 3, .height = 3, .rgba = {}};
  EXPECT_THROW(write_png(test::scratch_dir("viz_bad") / "x.png", broken), InvalidInput);
  Image ok{.width = 1, .height = 1, .rgba = {0, 0, 0, 255}};
  EXPECT_THROW(write_png("/nonexistent-dir/x/y.png", ok), IoError);
}

TEST(Colormap, EndsAndMonotoneLuminanceOfViridis) {
  auto lum = [](const Vec3& c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; };
  double prev = -1;
  for (int i = 0; i <= 100; ++i) {
    const double l = lum(colormap_rgb(Colormap::Viridis, i / 100.0));
    EXPECT_GT(l, prev);
    prev = l;
  }
  const Vec3 mid = colormap_rgb(Colormap::CoolWarm, 0.5);
  EXPECT_TRUE(test::near(mid[0], mid[2], 1e-9));  // neutral grey in the middle
  EXPECT_GT(colormap_rgb(Colormap::CoolWarm, 0)[2], colormap_rgb(Colormap::CoolWarm, 0)[0]);
  EXPECT_GT(colormap_rgb(Colormap::CoolWarm, 1)[0], colormap_rgb(Colormap::CoolWarm, 1)[2]);
}

}  // namespace
}  // namespace ido::viz
