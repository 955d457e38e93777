#pragma once
// The median every stage takes of a sample: robust to a minority of outliers and O(n).

#include <algorithm>
#include <cassert>
#include <cstddef>
#include <vector>

namespace alight {

/// The upper median of v: the value at index n / 2 of v sorted (of an even count the larger of
/// the two middle values), by std::nth_element. v must not be empty; callers decide what an
/// empty sample means (no estimate, a neutral value).
template <class T>
T upper_median(std::vector<T> v) {
  assert(!v.empty());
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace alight
