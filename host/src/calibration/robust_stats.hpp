// Order statistics shared by the calibration's image analysis and goal colours.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace omniloc::calibration_detail {

/// The q-quantile (0..1) of v by nth_element (no interpolation); 0 for an empty v.
inline double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

/// Robust standard deviation (1.4826 x median absolute deviation from the median).
inline double robust_sigma(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const double med = percentile(v, 0.5);
  for (double& x : v) x = std::abs(x - med);
  return 1.4826 * percentile(std::move(v), 0.5);
}

}  // namespace omniloc::calibration_detail
