// SPDX-License-Identifier: Apache-2.0
// The slice layout: which voxel a click lands on, millimetres square, the slice fitted into
// the view and centred, index axes per orientation as documented.
#include "ido/view/slice_view.h"

#include <cmath>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "support/test_support.h"

namespace ido {
namespace {

TEST(SliceView, PixelAndVoxelAreInverseAndMillimetresSquare) {
  const Index3 size = {40, 30, 20};
  const Vec3 spacing(0.8, 1.2, 2.5);
  for (int axis = 0; axis < 3; ++axis) {
    const view::SliceView v(axis, size, spacing, {100, 50, 400, 300});
    const int u = v.u_axis(), w = v.v_axis();
    EXPECT_NE(u, axis);
    EXPECT_NE(w, axis);
    EXPECT_NE(u, w);
    for (std::int64_t a = 0; a < size[std::size_t(u)]; a += 3)
      for (std::int64_t b = 0; b < size[std::size_t(w)]; b += 3) {
        const auto p = v.pixel_of(double(a), double(b));
        EXPECT_TRUE(v.rect().contains(p[0], p[1]));
        const auto back = v.voxel_at(p[0], p[1]);
        ASSERT_TRUE(back);
        EXPECT_EQ((*back)[0], a);
        EXPECT_EQ((*back)[1], b);
        // A quarter of a voxel off the centre still lands on the voxel.
        const auto near = v.voxel_at(p[0] + 0.24 * spacing[u] * v.scale_px_per_mm(), p[1]);
        ASSERT_TRUE(near);
        EXPECT_EQ((*near)[0], a);
      }
    // One voxel step is its spacing in pixels along each axis: millimetres are square.
    const auto p0 = v.pixel_of(0, 0), p1 = v.pixel_of(1, 1);
    EXPECT_TRUE(test::near(std::abs(p1[0] - p0[0]), spacing[u] * v.scale_px_per_mm(), 1e-9));
    EXPECT_TRUE(test::near(std::abs(p1[1] - p0[1]), spacing[w] * v.scale_px_per_mm(), 1e-9));
    // Outside the slice nothing is hit.
    EXPECT_FALSE(v.voxel_at(p0[0] - spacing[u] * v.scale_px_per_mm(), p0[1]));
  }
  // Axial: j grows downwards; coronal and sagittal: k grows upwards (superior up).
  const view::SliceView axial(2, size, spacing, {0, 0, 400, 300}), coronal(1, size, spacing, {0, 0, 400, 300});
  EXPECT_GT(axial.pixel_of(0, 5)[1], axial.pixel_of(0, 0)[1]);
  EXPECT_LT(coronal.pixel_of(0, 5)[1], coronal.pixel_of(0, 0)[1]);
}

TEST(SliceView, NdcMatrixMapsVoxelsWhereThePixelsAre) {
  const view::SliceView v(1, {40, 30, 20}, Vec3(0.8, 1.2, 2.5), {100, 50, 400, 300});
  const Mat4 m = v.ndc_from_index();
  for (const auto& [a, b] : {std::pair{0.0, 0.0}, {39.0, 19.0}, {12.5, 7.0}}) {
    const Vec4 ndc = m * Vec4(a, b, 0, 1);
    const auto p = v.pixel_of(a, b);
    EXPECT_TRUE(test::near(v.rect().x + (ndc.x() + 1) / 2 * v.rect().width, p[0], 1e-9));
    EXPECT_TRUE(test::near(v.rect().y + (1 - ndc.y()) / 2 * v.rect().height, p[1], 1e-9));
  }
}

TEST(SliceView, AxesFitAndCentreAsDocumented) {
  const Index3 size = {40, 30, 20};
  const Vec3 spacing(0.8, 1.2, 2.5);
  const view::PixelRect rect{100, 50, 400, 300};
  // Axial shows (i, j), coronal (i, k), sagittal (j, k).
  const int want_u[3] = {1, 0, 0}, want_v[3] = {2, 2, 1};
  for (int axis = 0; axis < 3; ++axis) {
    const view::SliceView v(axis, size, spacing, rect);
    EXPECT_EQ(v.axis(), axis);
    EXPECT_EQ(v.u_axis(), want_u[axis]) << axis;
    EXPECT_EQ(v.v_axis(), want_v[axis]) << axis;
    const int u = v.u_axis(), w = v.v_axis();
    // The slice's outer corners (index −0.5 and size − 0.5) lie in the view, and along one
    // axis they touch both sides: fitted, as large as it can be.
    const auto p0 = v.pixel_of(-0.5, -0.5);
    const auto p1 = v.pixel_of(double(size[std::size_t(u)]) - 0.5, double(size[std::size_t(w)]) - 0.5);
    const double left = std::min(p0[0], p1[0]), right = std::max(p0[0], p1[0]);
    const double top = std::min(p0[1], p1[1]), bottom = std::max(p0[1], p1[1]);
    EXPECT_GE(left, rect.x - 1e-9);
    EXPECT_LE(right, rect.x + rect.width + 1e-9);
    EXPECT_GE(top, rect.y - 1e-9);
    EXPECT_LE(bottom, rect.y + rect.height + 1e-9);
    const bool fills_width = test::near(right - left, rect.width, 1e-9);
    const bool fills_height = test::near(bottom - top, rect.height, 1e-9);
    EXPECT_TRUE(fills_width || fills_height) << axis;
    // Centred.
    EXPECT_TRUE(test::near(0.5 * (left + right), rect.x + 0.5 * rect.width, 1e-9));
    EXPECT_TRUE(test::near(0.5 * (top + bottom), rect.y + 0.5 * rect.height, 1e-9));
    // The scale is the fitted extent over the slice's millimetres.
    EXPECT_TRUE(test::near(right - left, double(size[std::size_t(u)]) * spacing[u] * v.scale_px_per_mm(), 1e-9));
    // Pixels beside the slice (inside the view's margins) hit nothing.
    EXPECT_FALSE(v.voxel_at(left - 0.5, 0.5 * (top + bottom)));
    EXPECT_FALSE(v.voxel_at(right + 0.5, 0.5 * (top + bottom)));
    EXPECT_FALSE(v.voxel_at(0.5 * (left + right), top - 0.5));
    EXPECT_FALSE(v.voxel_at(0.5 * (left + right), bottom + 0.5));
  }
  // Sagittal: j grows to the right, k upwards.
  const view::SliceView sagittal(0, size, spacing, rect);
  EXPECT_GT(sagittal.pixel_of(5, 0)[0], sagittal.pixel_of(0, 0)[0]);
  EXPECT_LT(sagittal.pixel_of(0, 5)[1], sagittal.pixel_of(0, 0)[1]);
}

TEST(SliceView, RefusesAnAxisOtherThanZeroOneOrTwo) {
  for (const int axis : {-1, 3}) {
    try {
      (void)view::SliceView(axis, {4, 4, 4}, Vec3(1, 1, 1), {0, 0, 100, 100});
      FAIL() << axis << " accepted";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("axis"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace ido
