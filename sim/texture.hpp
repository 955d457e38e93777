#pragma once
// Surface textures for the renderer: procedural (seeded) or from an image, stored as a mip-map
// pyramid so that a surface seen from far away or at a grazing angle is filtered instead of
// aliasing (Williams, "Pyramidal parametrics", SIGGRAPH 1983: trilinear mip-map sampling).
// Textures tile: coordinates wrap, so a 4 m tile covers any floor.

#include <bit>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "sim/params.hpp"

namespace alight::sim {

class Texture {
 public:
  /// Builds the texture a spec describes; procedural kinds draw from `seed` (the scenario seed
  /// combined with the spec's own seed), image kinds use spec.image.
  static Texture make(const TextureSpec& spec, uint64_t seed);
  /// A texture from grey pixels (any size; resized to powers of two for wrapping).
  static Texture from_image(const cv::Mat& mono8, double texel_m);

  /// Grey level at surface coordinates (u, v) [m] for a pixel footprint on the surface [m].
  float sample(float u_m, float v_m, float footprint_m) const {
    float level = fast_log2(footprint_m * inv_texel_m_);
    if (level <= 0.f) return bilinear(0, u_m * inv_texel_m_, v_m * inv_texel_m_);
    const int max_level = static_cast<int>(levels_.size()) - 1;
    if (level >= static_cast<float>(max_level)) {
      const float s = inv_texel_m_ / static_cast<float>(1 << max_level);
      return bilinear(max_level, u_m * s, v_m * s);
    }
    const int l0 = static_cast<int>(level);
    const float f = level - static_cast<float>(l0);
    const float s0 = inv_texel_m_ / static_cast<float>(1 << l0);
    const float a = bilinear(l0, u_m * s0, v_m * s0);
    const float b = bilinear(l0 + 1, u_m * s0 * 0.5f, v_m * s0 * 0.5f);
    return a + f * (b - a);
  }

  /// Level i of the pyramid: continuous, (cols >> i) x (rows >> i).
  const cv::Mat& level(int i) const { return levels_[i].pixels; }
  int n_levels() const { return static_cast<int>(levels_.size()); }
  double texel_m() const { return 1.0 / inv_texel_m_; }
  /// Texels per metre, exactly as sample() uses it (the renderer's batched sampling mirrors it).
  float inv_texel_m() const { return inv_texel_m_; }
  /// An image's: its edges meet at seams where it repeats (the procedural kinds are periodic,
  /// without seams).
  bool has_seams() const { return has_seams_; }

  static float fast_log2(float x) {
    // Mip level selection needs about 0.1 of a level: log2 from the float's exponent and a
    // quadratic in its mantissa.
    // Signed bits: the renderer's SIMD passes call this, and GCC 12 does not vectorise the
    // unsigned-to-int conversion (& 255 makes the shift's sign irrelevant).
    const int bits = std::bit_cast<int>(x);
    const int e = ((bits >> 23) & 255) - 127;
    const float m = std::bit_cast<float>((bits & 0x7fffff) | 0x3f800000) - 1.f;  // [0, 1)
    return static_cast<float>(e) + m * (1.3465f - 0.3465f * m);
  }

 private:
  struct Level {
    cv::Mat pixels;  // CV_8U: a quarter of the memory traffic of float
    int mask_x = 0, mask_y = 0;
  };
  float bilinear(int l, float x, float y) const {
    const Level& L = levels_[l];
    x -= 0.5f;
    y -= 0.5f;
    // floor() without a libm call (x86-64 baseline has no roundss).
    int ix = static_cast<int>(x), iy = static_cast<int>(y);
    ix -= x < static_cast<float>(ix);
    iy -= y < static_cast<float>(iy);
    const float fx = x - static_cast<float>(ix), fy = y - static_cast<float>(iy);
    const int x0 = ix & L.mask_x, y0 = iy & L.mask_y;
    const int x1 = (x0 + 1) & L.mask_x, y1 = (y0 + 1) & L.mask_y;
    const uint8_t* r0 = L.pixels.ptr<uint8_t>(y0);
    const uint8_t* r1 = L.pixels.ptr<uint8_t>(y1);
    const float a00 = r0[x0], a01 = r0[x1], a10 = r1[x0], a11 = r1[x1];
    const float a = a00 + fx * (a01 - a00);
    const float b = a10 + fx * (a11 - a10);
    return a + fy * (b - a);
  }
  void build_pyramid(const cv::Mat& base8u);

  std::vector<Level> levels_;
  float inv_texel_m_ = 250.f;
  bool has_seams_ = false;
};

/// The procedural textures, exposed for tests: a size_px x size_px mono8 tile that wraps.
cv::Mat make_procedural_texture(const TextureSpec& spec, uint64_t seed);

}  // namespace alight::sim
