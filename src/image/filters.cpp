// SPDX-License-Identifier: Apache-2.0
// Separable Gaussian smoothing, finite-difference gradients and robust statistics; the
// project's own straightforward implementations (no algorithm beyond the textbook ones).
#include "ido/image/filters.h"
#include "ido/image/index_box.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "ido/core/error.h"
#include "ido/core/parallel.h"
#include "ido/core/statistics.h"

namespace ido::image {
namespace {

/// One 1D convolution along @p axis with border replication, from @p src into @p dst (both
/// nx·ny·nz voxels, not overlapping). Every output voxel is the kernel-weighted sum of its
/// neighbours along the axis, accumulated from the kernel's first tap to its last; the loops
/// run along i in the innermost position on every axis so the compiler vectorises them
/// (the same additions in the same order per voxel, so the same floats as a per-voxel loop).
void convolve_axis(const float* src, float* dst, const Index3& size, int axis, const std::vector<float>& kernel,
                   bool threaded) {
  const std::int64_t nx = size[0], ny = size[1], nz = size[2];
  const int half = static_cast<int>(kernel.size() / 2);
  const std::size_t rows = static_cast<std::size_t>(ny * nz);
  const std::size_t row_len = static_cast<std::size_t>(nx);
  if (axis == 0) {
    parallel_for_ranges(
        rows,
        [&](std::size_t b, std::size_t e) {
          std::vector<float> padded(static_cast<std::size_t>(nx + 2 * half));
          for (std::size_t r = b; r < e; ++r) {
            const float* row = src + r * row_len;
            for (std::int64_t i = -half; i < nx + half; ++i)
              padded[static_cast<std::size_t>(i + half)] = row[std::clamp<std::int64_t>(i, 0, nx - 1)];
            float* orow = dst + r * row_len;
            std::fill(orow, orow + nx, 0.f);
            for (std::size_t m = 0; m < kernel.size(); ++m) {
              const float w = kernel[m];
              const float* p = padded.data() + m;
              for (std::size_t i = 0; i < row_len; ++i) orow[i] += w * p[i];
            }
          }
        },
        threaded, 16);
    return;
  }
  // Along j or k every output row is a weighted sum of whole input rows (contiguous in i).
  parallel_for_ranges(
      rows,
      [&](std::size_t b, std::size_t e) {
        for (std::size_t r = b; r < e; ++r) {
          const std::int64_t j = static_cast<std::int64_t>(r) % ny;
          const std::int64_t k = static_cast<std::int64_t>(r) / ny;
          float* orow = dst + r * row_len;
          std::fill(orow, orow + nx, 0.f);
          for (int m = -half; m <= half; ++m) {
            const std::int64_t jj = axis == 1 ? std::clamp<std::int64_t>(j + m, 0, ny - 1) : j;
            const std::int64_t kk = axis == 2 ? std::clamp<std::int64_t>(k + m, 0, nz - 1) : k;
            const float w = kernel[static_cast<std::size_t>(m + half)];
            const float* irow = src + static_cast<std::size_t>(jj + ny * kk) * row_len;
            for (std::size_t i = 0; i < row_len; ++i) orow[i] += w * irow[i];
          }
        }
      },
      threaded, 16);
}

/// Index-space derivative along @p axis at (i, j, k): central, one-sided on the border,
/// in intensity units per voxel.
inline double index_derivative(const Volume<float>& v, std::int64_t i, std::int64_t j,
                               std::int64_t k, int axis) {
  const std::int64_t n = v.size(axis);
  if (n < 2) return 0.0;
  std::int64_t idx[3] = {i, j, k};
  const std::int64_t c = idx[axis];
  const std::int64_t lo = std::max<std::int64_t>(c - 1, 0), hi = std::min<std::int64_t>(c + 1, n - 1);
  idx[axis] = hi;
  const double fh = v(idx[0], idx[1], idx[2]);
  idx[axis] = lo;
  const double fl = v(idx[0], idx[1], idx[2]);
  return (fh - fl) / static_cast<double>(hi - lo);
}

template <class Out, class Store>
Volume<Out> gradient_impl(const Volume<float>& v, bool threaded, Out fill, Store store) {
  Volume<Out> out = v.like<Out>(fill);
  // ∇_world f = J^{-T} ∇_index f, where J = D·diag(spacing) maps index to world offsets.
  const Mat3 jit = v.world_to_index_matrix().transpose();
  const std::int64_t nx = v.size(0), ny = v.size(1);
  const std::int64_t nz = v.size(2);
  parallel_for_ranges(
      static_cast<std::size_t>(ny * nz),
      [&](std::size_t b, std::size_t e) {
        for (std::size_t r = b; r < e; ++r) {
          const std::int64_t j = static_cast<std::int64_t>(r) % ny;
          const std::int64_t k = static_cast<std::int64_t>(r) / ny;
          auto at_border = [&](std::int64_t i) {
            const Vec3 gi(index_derivative(v, i, j, k, 0), index_derivative(v, i, j, k, 1),
                          index_derivative(v, i, j, k, 2));
            out(i, j, k) = store(Vec3(jit * gi));
          };
          if (j == 0 || j == ny - 1 || k == 0 || k == nz - 1 || nx < 3) {
            for (std::int64_t i = 0; i < nx; ++i) at_border(i);
            continue;
          }
          // Inside the grid every difference is central: the same values as index_derivative,
          // read straight from the five neighbouring rows.
          const float* row = &v(0, j, k);
          const float* jm = &v(0, j - 1, k);
          const float* jp = &v(0, j + 1, k);
          const float* km = &v(0, j, k - 1);
          const float* kp = &v(0, j, k + 1);
          at_border(0);
          for (std::int64_t i = 1; i < nx - 1; ++i) {
            const Vec3 gi((double(row[i + 1]) - double(row[i - 1])) / 2.0, (double(jp[i]) - double(jm[i])) / 2.0,
                          (double(kp[i]) - double(km[i])) / 2.0);
            out(i, j, k) = store(Vec3(jit * gi));
          }
          at_border(nx - 1);
        }
      },
      threaded, 16);
  return out;
}

}  // namespace

std::vector<float> gaussian_kernel(double sigma_vox, double truncate) {
  const int half = std::max(1, static_cast<int>(std::ceil(truncate * sigma_vox)));
  std::vector<double> w(static_cast<std::size_t>(2 * half + 1));
  double sum = 0.0;
  for (int m = -half; m <= half; ++m) {
    const double v = std::exp(-0.5 * (m * m) / (sigma_vox * sigma_vox));
    w[static_cast<std::size_t>(m + half)] = v;
    sum += v;
  }
  std::vector<float> out(w.size());
  for (std::size_t n = 0; n < w.size(); ++n) out[n] = static_cast<float>(w[n] / sum);
  return out;
}

Volume<float> gaussian_smooth(const Volume<float>& volume, const Vec3& sigma_mm_per_axis,
                              const GaussianOptions& options) {
  for (int a = 0; a < 3; ++a)
    if (!(sigma_mm_per_axis[a] >= 0.0) || !std::isfinite(sigma_mm_per_axis[a]))
      throw InvalidInput("gaussian_smooth: sigma must be a finite number of mm >= 0, got " +
                         std::to_string(sigma_mm_per_axis[a]));
  if (!(options.truncate_sigmas >= 1.0))
    throw InvalidInput("gaussian_smooth: truncate_sigmas must be >= 1");
  if (volume.empty()) return volume;
  // The passes read the input and then ping-pong between two buffers: no copy of the input,
  // and two fresh volumes whatever the number of passes (each fresh one costs its page faults).
  std::vector<std::pair<int, std::vector<float>>> passes;
  for (int a = 0; a < 3; ++a) {
    if (volume.size(a) < 2) continue;
    const double sigma_vox = sigma_mm_per_axis[a] / volume.spacing()[a];
    if (sigma_vox < 1e-3) continue;  // kernel is a delta to float precision
    passes.emplace_back(a, gaussian_kernel(sigma_vox, options.truncate_sigmas));
  }
  if (passes.empty()) return volume;
  Volume<float> out = volume.like<float>();
  Volume<float> spare = passes.size() > 1 ? volume.like<float>() : Volume<float>();
  // With two passes the first goes to the spare buffer, with one or three to the output, so
  // that the last one lands in the output.
  Volume<float>* write = passes.size() == 2 ? &spare : &out;
  Volume<float>* other = passes.size() == 2 ? &out : &spare;
  const float* read = volume.data().data();
  for (const auto& [axis, kernel] : passes) {
    convolve_axis(read, write->data().data(), volume.size(), axis, kernel, options.threaded);
    read = write->data().data();
    std::swap(write, other);
  }
  return out;
}

Volume<float> gaussian_smooth(const Volume<float>& volume, double sigma_mm,
                              const GaussianOptions& options) {
  if (!(sigma_mm >= 0.0) || !std::isfinite(sigma_mm))
    throw InvalidInput("gaussian_smooth: sigma must be a finite number of mm >= 0, got " +
                       std::to_string(sigma_mm));
  return gaussian_smooth(volume, Vec3::Constant(sigma_mm), options);
}

Volume<Vec3f> gradient(const Volume<float>& volume, bool threaded) {
  return gradient_impl<Vec3f>(volume, threaded, Vec3f::Zero(), [](const Vec3& g) { return Vec3f(g.cast<float>()); });
}

Volume<float> gradient_magnitude(const Volume<float>& volume, bool threaded) {
  return gradient_impl<float>(volume, threaded, 0.f,
                              [](const Vec3& g) { return static_cast<float>(g.norm()); });
}

RobustStats robust_stats(std::vector<double> values) {
  if (values.empty()) throw InvalidInput("robust statistics of an empty sample");
  RobustStats s;
  s.count = values.size();
  s.median = median(values);
  for (double& v : values) v = std::abs(v - s.median);
  s.mad = median(std::move(values));
  return s;
}

RobustStats robust_stats_in_ball(const Volume<float>& volume, const Vec3& centre_mm,
                                 double radius_mm) {
  if (volume.empty()) throw InvalidInput("robust_stats_in_ball: empty volume");
  if (!(radius_mm >= 0.0) || !std::isfinite(radius_mm))
    throw InvalidInput("robust_stats_in_ball: radius must be a finite number of mm >= 0");
  const Vec3 c = volume.world_to_index(centre_mm);
  for (int a = 0; a < 3; ++a)
    if (!(c[a] >= -0.5 && c[a] <= double(volume.size(a)) - 0.5))
      throw InvalidInput("robust_stats_in_ball: centre lies outside the volume");
  std::vector<double> values;
  for_each_voxel_in_ball(volume, centre_mm, radius_mm,
                         [&](std::int64_t i, std::int64_t j, std::int64_t k) { values.push_back(volume(i, j, k)); });
  if (values.empty()) {
    const auto clampi = [&](int a) {
      return std::clamp<std::int64_t>(std::llround(c[a]), 0, volume.size(a) - 1);
    };
    values.push_back(volume(clampi(0), clampi(1), clampi(2)));
  }
  return robust_stats(std::move(values));
}

}  // namespace ido::image
