#pragma once
// Quantiles for the benches' reports: linear interpolation between order statistics (the
// "type 7" definition of R and numpy's default), NaN for no samples, so an empty set prints as
// "nan" and never as a measured 0.

#include <algorithm>
#include <cmath>
#include <vector>

namespace alight::test {

inline double quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const size_t i = static_cast<size_t>(pos);
  const double f = pos - static_cast<double>(i);
  return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
}

}  // namespace alight::test
