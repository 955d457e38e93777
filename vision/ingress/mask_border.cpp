// The border of a mask as a list of pixels; see mask_border.hpp.
#include "vision/ingress/mask_border.hpp"

#include <algorithm>
#include <cassert>
#include <cstring>

#include "vision/simd.hpp"

namespace alight::vision {
namespace {

// flags[x] = 1 where a pixel of rows up, mid, down in columns x - 1 .. x + 1 differs from
// mid[x] (columns past the ends left out); the rows above the first and below the last are
// passed as the row itself, which adds nothing.
ALIGHT_MULTIVERSION
void row_flags(const uint8_t* __restrict up, const uint8_t* __restrict mid,
               const uint8_t* __restrict down, int cols, uint8_t* __restrict flags) {
  for (int x = 1; x < cols - 1; ++x) {
    const uint8_t c = mid[x];
    flags[x] = (up[x - 1] != c) | (up[x] != c) | (up[x + 1] != c) | (mid[x - 1] != c) |
               (mid[x + 1] != c) | (down[x - 1] != c) | (down[x] != c) | (down[x + 1] != c);
  }
  for (const int x : {0, cols - 1}) {  // the same column twice when cols is 1
    const uint8_t c = mid[x];
    uint8_t f = 0;
    for (int k = std::max(0, x - 1); k <= std::min(cols - 1, x + 1); ++k)
      f |= (up[k] != c) | (mid[k] != c) | (down[k] != c);
    flags[x] = f;
  }
}

}  // namespace

std::vector<cv::Point> mask_border_pixels(const cv::Mat& mask) {
  assert(mask.empty() || mask.type() == CV_8UC1);
  std::vector<cv::Point> out;
  if (mask.empty()) return out;
  std::vector<uint8_t> flags(mask.cols, 0);
  for (int y = 0; y < mask.rows; ++y) {
    const uint8_t* mid = mask.ptr<uint8_t>(y);
    const uint8_t* up = y > 0 ? mask.ptr<uint8_t>(y - 1) : mid;
    const uint8_t* down = y + 1 < mask.rows ? mask.ptr<uint8_t>(y + 1) : mid;
    row_flags(up, mid, down, mask.cols, flags.data());
    // Most of a row is inside or outside the mask: skip 16 clear flags at a time.
    for (int x = 0; x < mask.cols; x += 16) {
      const int n = std::min(16, mask.cols - x);
      if (n == 16) {
        uint64_t a, b;
        std::memcpy(&a, flags.data() + x, 8);
        std::memcpy(&b, flags.data() + x + 8, 8);
        if (!(a | b)) continue;
      }
      for (int k = 0; k < n; ++k)
        if (flags[x + k]) out.emplace_back(x + k, y);
    }
  }
  return out;
}

}  // namespace alight::vision
