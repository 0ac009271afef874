// SPDX-License-Identifier: Apache-2.0
// The ITK peers of bench_segment behind a plain interface: ITK's bundled Eigen clashes with
// the system Eigen of ido's headers, so ITK is included only by itk_level_set_peer.cpp and
// this header uses standard types only.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

namespace ido::bench {

/// A float volume as ITK sees it (LPS, x fastest): the buffer is borrowed, not copied.
struct PeerImage {
  std::array<std::int64_t, 3> size{};
  std::array<double, 3> spacing{1, 1, 1};  ///< mm
  std::array<double, 3> origin{};          ///< mm
  std::array<double, 9> direction{1, 0, 0, 0, 1, 0, 0, 0, 1};  ///< row-major
  const float* voxels = nullptr;           ///< size[0]·size[1]·size[2] values
};

/// Parameters shared by the two ITK level-set filters. Defaults follow the ITK Software
/// Guide's examples (§9.3.3 GeodesicActiveContour, §9.3.5 ThresholdSegmentationLevelSet).
struct PeerOptions {
  std::array<std::int64_t, 3> seed_index{};  ///< voxel index of the seed
  double initial_radius_mm = 3.0;  ///< initial front: fast-marching distance from the seed
  double lower = 0, upper = 0;     ///< threshold filter: accepted intensity band
  double curvature_scaling = 1.0;
  double propagation_scaling = 1.0;
  double advection_scaling = 1.0;   ///< geodesic active contour only
  double gradient_sigma_mm = 1.0;   ///< geodesic active contour: gradient-magnitude σ
  double sigmoid_alpha = -1.0;      ///< geodesic active contour: edge potential sigmoid
  double sigmoid_beta = 1.0;        ///< (intensity units per mm of gradient magnitude)
  double max_rms_change = 0.02;
  int max_iterations = 1000;
};

/// An ITK result: 1 where the output level set is ≤ 0 (inside), x fastest.
struct PeerResult {
  std::vector<std::uint8_t> inside;
  int iterations = 0;
  double rms_change = 0;
};

/// itk::ThresholdSegmentationLevelSetImageFilter from a fast-marching initial front.
[[nodiscard]] PeerResult itk_threshold_level_set(const PeerImage& image, const PeerOptions& options);
/// itk::GeodesicActiveContourLevelSetImageFilter on the sigmoid of the gradient magnitude
/// (itk::GradientMagnitudeRecursiveGaussianImageFilter), same initial front.
[[nodiscard]] PeerResult itk_geodesic_active_contour(const PeerImage& image, const PeerOptions& options);

}  // namespace ido::bench
