// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <vector>

namespace ido {

/// The @p q quantile (0 ≤ q ≤ 1) of a sample: linear interpolation between the order
/// statistics on either side of rank q·(n − 1) (Hyndman & Fan's type 7, numpy's default), so
/// a figure can be checked with numpy.percentile. The one percentile of ido: timing
/// percentiles, HD95, file statistics and medians all use it.
/// @throws ido::InvalidInput on an empty sample or a q outside [0, 1].
[[nodiscard]] double percentile(std::vector<double> values, double q);

/// Several quantiles of one sample, in the order of @p qs: each one as percentile() gives it,
/// by selections over what is left of the sample (no whole sort), so a volume's voxels can be
/// summarised without a second copy at double precision (the float overload).
/// @throws ido::InvalidInput as percentile().
[[nodiscard]] std::vector<double> percentiles(std::vector<double> values, const std::vector<double>& qs);
[[nodiscard]] std::vector<double> percentiles(std::vector<float> values, const std::vector<double>& qs);

/// percentile(values, 0.5): the middle value, or the mean of the two middle values.
[[nodiscard]] double median(std::vector<double> values);

}  // namespace ido
