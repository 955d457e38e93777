#include "sim/renderer.hpp"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

namespace alight::sim {

namespace {
constexpr int kTile = 16;
constexpr float kNear = 1e-3f;          // [m] along the optical axis
constexpr int kMaxRun = kTile * 4 * 4;  // rays of a tile's row at the largest supersampling
constexpr int kMaxLevels = 32;          // of a texture's mip-map pyramid

struct BoxFrame {     // one box, prepared for one frame
  float M[9];         // camera direction -> box frame
  float o[3];         // camera centre in the box frame
  float h[3];         // half sizes
  float shade[6];     // per face: axis * 2 + (positive side)
  float shadowed[6];  // per face: the share of its shade left in a cast shadow (the ambient's)
  float reflectance;  // its top face mirrors the sky (Box::reflectance); 0: matte
  Vector3d up_W;      // its top face's normal
  float lamp[3];      // the lamp in the box frame
  float near_range;   // no point of the box is closer to the camera [m]
  int texture;        // index into Scene::textures
  bool visible;
  bool straddles;                 // has corners behind the camera: may cover any tile
  float x0, y0, x1, y1;           // bounds of its projection on the z = 1 plane
  std::vector<cv::Point2f> hull;  // its silhouette on the z = 1 plane (convex), when not straddling
};

// Whether the axis-aligned rectangle b = (x0, y0, x1, y1) meets the convex polygon `hull`
// (counter-clockwise or clockwise): separating axes of the polygon's edges; the rectangle's own
// axes were checked with the bounds.
bool rect_meets_hull(const cv::Vec4f& b, const std::vector<cv::Point2f>& hull, float orientation) {
  const cv::Point2f corners[4] = {{b[0], b[1]}, {b[2], b[1]}, {b[2], b[3]}, {b[0], b[3]}};
  for (size_t i = 0; i < hull.size(); ++i) {
    const cv::Point2f& p = hull[i];
    const cv::Point2f e = hull[(i + 1) % hull.size()] - p;
    bool all_outside = true;
    for (const auto& c : corners) {
      const float cross = e.x * (c.y - p.y) - e.y * (c.x - p.x);
      if (cross * orientation >= 0.f) {
        all_outside = false;
        break;
      }
    }
    if (all_outside) return false;
  }
  return true;
}

// A texture as the batched sampling below sees it: the parameters of Texture::sample().
struct SurfaceTex {
  float inv_texel;   // texels per metre
  float cols, rows;  // of level 0 (powers of two)
  float max_level;
  int id;  // index into the frame's level pointers
  // Where a box's top reads the texture at its centre [m]: an image's centre, so that a
  // photograph printed on a top (at least its size) is seen whole, not rolled about the
  // texture's origin with its four corners and their seams meeting at the top's centre; 0 for
  // the procedural kinds, which have no seams.
  float top_u0, top_v0;
};

// The passes over a row's rays below are plain loops over arrays, written so that the compiler
// turns them into SIMD code: selects instead of branches, integer results blended with
// bit masks (a float comparison selecting an int does not vectorise with GCC 12 on SSE2).
// On x86-64 each is also built for AVX2 (x86-64-v3) and AVX-512 (x86-64-v4), picked at load
// time by what the processor has: two and four times the lanes. Floating-point contraction is
// off for this file (sim/CMakeLists.txt), so every version renders bit-identical images.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define ALIGHT_SIMD_PASS [[gnu::target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")]]
#else
#define ALIGHT_SIMD_PASS
#endif

// Ray parameter of the floor (z = 0) seen from above, infinity for rays that miss it.
ALIGHT_SIMD_PASS void floor_pass(int count, const float* __restrict rx, const float* __restrict ry,
                                 const float* Rw, float Cz, float* __restrict th,
                                 int* __restrict hb, int* __restrict ha) {
  const float inf = std::numeric_limits<float>::infinity();
  const float num = Cz > 0.f ? -Cz : 0.f;
  const float R6 = Rw[6], R7 = Rw[7], R8 = Rw[8];
  for (int k = 0; k < count; ++k) {
    const float dwz = R6 * rx[k] + R7 * ry[k] + R8;
    const float t = num / std::min(dwz, -1e-6f);
    th[k] = ((dwz < -1e-6f) & (Cz > 0.f)) ? t : inf;
    hb[k] = -1;
    ha[k] = 0;
  }
}

// Slab test of one box (Kay and Kajiya) for the rays [k0, k1): where it is hit nearer than th,
// th, hb (the box's index) and ha (the axis of the face the ray enters) are replaced. Returns
// whether any ray hit it.
ALIGHT_SIMD_PASS bool box_pass(int k0, int k1, const float* __restrict rx,
                               const float* __restrict ry, const float* M, const float* o,
                               const float* h, int id, float* __restrict th, int* __restrict hb,
                               int* __restrict ha) {
  const float M0 = M[0], M1 = M[1], M2 = M[2], M3 = M[3], M4 = M[4], M5 = M[5], M6 = M[6],
              M7 = M[7], M8 = M[8];
  const float lo0 = -h[0] - o[0], hi0 = h[0] - o[0];
  const float lo1 = -h[1] - o[1], hi1 = h[1] - o[1];
  const float lo2 = -h[2] - o[2], hi2 = h[2] - o[2];
  int any = 0;
  for (int k = k0; k < k1; ++k) {
    float d0 = M0 * rx[k] + M1 * ry[k] + M2;
    float d1 = M3 * rx[k] + M4 * ry[k] + M5;
    float d2 = M6 * rx[k] + M7 * ry[k] + M8;
    // A component of exactly zero would turn the shared reciprocal below into NaN.
    d0 = std::abs(d0) < 1e-12f ? 1e-12f : d0;
    d1 = std::abs(d1) < 1e-12f ? 1e-12f : d1;
    d2 = std::abs(d2) < 1e-12f ? 1e-12f : d2;
    // One division for the three reciprocals (1/d0 = d1 d2 / (d0 d1 d2), ...).
    const float p01 = d0 * d1, inv_all = 1.f / (p01 * d2);
    const float i0 = d1 * d2 * inv_all, i1 = d0 * d2 * inv_all, i2 = p01 * inv_all;
    const float a0 = lo0 * i0, b0 = hi0 * i0, a1 = lo1 * i1, b1 = hi1 * i1;
    const float a2 = lo2 * i2, b2 = hi2 * i2;
    const float n0 = std::min(a0, b0), n1 = std::min(a1, b1), n2 = std::min(a2, b2);
    const float tmin = std::max(std::max(n0, n1), n2);
    const float tmax = std::min(std::min(std::max(a0, b0), std::max(a1, b1)), std::max(a2, b2));
    // The entry face: the slab entered last (the first one on ties).
    const int later2 = -static_cast<int>(n2 > std::max(n0, n1));
    const int later1 = -static_cast<int>(n1 > n0);
    const int axis = (2 & later2) | (1 & later1 & ~later2);
    const float old = th[k];
    const int m = -static_cast<int>(tmin <= tmax) & -static_cast<int>(tmin > kNear) &
                  -static_cast<int>(tmin < old);
    th[k] = m ? tmin : old;
    hb[k] = (id & m) | (hb[k] & ~m);
    ha[k] = (axis & m) | (ha[k] & ~m);
    any |= m;
  }
  return any != 0;
}

// Floor coordinates, footprint and shade (with the lamp's falloff) of every ray.
ALIGHT_SIMD_PASS void floor_coords_pass(
    int count, const float* __restrict rx, const float* __restrict ry, const float* __restrict rlen,
    const float* __restrict rscale, const float* __restrict th, const float* Rw, float Cx, float Cy,
    float floor_shade, const float* lamp, const SurfaceTex& tex, float* __restrict tu,
    float* __restrict tv, float* __restrict fp, float* __restrict sh, float* __restrict tinv,
    float* __restrict tcols, float* __restrict trows, float* __restrict tmax, int* __restrict tid) {
  const float R0 = Rw[0], R1 = Rw[1], R2 = Rw[2], R3 = Rw[3], R4 = Rw[4], R5 = Rw[5], R6 = Rw[6],
              R7 = Rw[7], R8 = Rw[8];
  // lamp: x, y, z^2 of the lamp, r^2, a, b of Renderer::render_rows.
  const float Lx = lamp[0], Ly = lamp[1], Lz2 = lamp[2], r2 = lamp[3], la = lamp[4], lb = lamp[5];
  for (int k = 0; k < count; ++k) {
    const float t = th[k];
    const float dwz = R6 * rx[k] + R7 * ry[k] + R8;
    const float px = Cx + t * (R0 * rx[k] + R1 * ry[k] + R2);
    const float py = Cy + t * (R3 * rx[k] + R4 * ry[k] + R5);
    const float cosi = std::max(0.05f, -dwz / rlen[k]);
    tu[k] = px;
    tv[k] = py;
    fp[k] = t * rscale[k] / std::sqrt(cosi);
    const float ex = px - Lx, ey = py - Ly;  // without a lamp the factor is exactly 1
    sh[k] = floor_shade * (lb + la / (r2 + ex * ex + ey * ey + Lz2));
    tinv[k] = tex.inv_texel;
    tcols[k] = tex.cols;
    trows[k] = tex.rows;
    tmax[k] = tex.max_level;
    tid[k] = tex.id;
  }
}

// A box that blocks the light (LightingParams::shadows), prepared for one frame: world points
// and the light's direction in its frame.
struct Occluder {
  Matrix3d R_OW;
  Vector3d c_W, h, l_O;
};

// Whether the way from p_W towards the light (l_O in the box's frame) passes through the box:
// a slab test along it beyond a millimetre, so a surface does not shadow itself.
bool blocks(const Occluder& o, const Vector3d& p_W) {
  const Vector3d q = o.R_OW * (p_W - o.c_W);
  double t0 = 1e-3, t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (std::abs(o.l_O[a]) < 1e-12) {
      if (std::abs(q[a]) > o.h[a]) return false;
      continue;
    }
    const double ta = (-o.h[a] - q[a]) / o.l_O[a], tb = (o.h[a] - q[a]) / o.l_O[a];
    t0 = std::max(t0, std::min(ta, tb));
    t1 = std::min(t1, std::max(ta, tb));
    if (t0 > t1) return false;
  }
  return true;
}

// Cast shadows: the rays whose surface point sees an occluder towards the light keep only the
// ambient share of their shade (floor_shadowed on the floor, the face's on a box). Scalar, and
// run only for scenes with shadows.
void shadow_pass(int count, const float* rx, const float* ry, const float* th, const int* hb,
                 const int* ha, const Matrix3d& R_WC, const Vector3d& C_W,
                 const std::vector<BoxFrame>& boxes, float floor_shadowed,
                 const std::vector<Occluder>& occluders, float* sh) {
  for (int k = 0; k < count; ++k) {
    const float t = th[k];
    if (!std::isfinite(t)) continue;
    float share = floor_shadowed;
    if (hb[k] >= 0) {
      const BoxFrame& f = boxes[hb[k]];
      const int a = ha[k];
      const float q = f.o[a] + t * (f.M[a * 3] * rx[k] + f.M[a * 3 + 1] * ry[k] + f.M[a * 3 + 2]);
      share = f.shadowed[a * 2 + (q > 0 ? 1 : 0)];
    }
    if (share >= 1.f) continue;  // facing away from the light: no direct light to lose
    const Vector3d p_W = C_W + double(t) * (R_WC * Vector3d(rx[k], ry[k], 1.0));
    for (const Occluder& o : occluders) {
      if (blocks(o, p_W)) {
        sh[k] *= share;
        break;
      }
    }
  }
}

// A reflective top (ReflectionParams) on the rays that hit one: the mirrored share F of the value
// becomes the sky's, where the ray reflected about the top's normal meets the plane z = sky_z,
// its footprint grown by the longer way there. F is Schlick's approximation of Fresnel's
// reflectance, r0 + (1 - r0)(1 - cos i)^5. Scalar, and run only for scenes with such a top.
void reflection_pass(int count, const float* rx, const float* ry, const float* th, const int* hb,
                     const int* ha, const float* foot, const Matrix3d& R_WC, const Vector3d& C_W,
                     const std::vector<BoxFrame>& boxes, const Texture& sky, double sky_z,
                     float sky_gain, float* value) {
  for (int k = 0; k < count; ++k) {
    const float t = th[k];
    if (hb[k] < 0 || ha[k] != 2 || !std::isfinite(t)) continue;
    const BoxFrame& f = boxes[hb[k]];
    if (f.reflectance <= 0.f) continue;
    const float q = f.o[2] + t * (f.M[6] * rx[k] + f.M[7] * ry[k] + f.M[8]);
    if (q <= 0) continue;  // the bottom face
    const Vector3d d_W = R_WC * Vector3d(rx[k], ry[k], 1.0);
    const double range = double(t) * d_W.norm();
    const Vector3d p_W = C_W + double(t) * d_W;
    const Vector3d d = d_W.normalized();
    const double cos_i = std::clamp(-d.dot(f.up_W), 0.0, 1.0);
    const Vector3d r_W = d + 2.0 * cos_i * f.up_W;
    if (r_W.z() <= 1e-6 || p_W.z() >= sky_z) continue;  // the mirror shows no sky
    const double s = (sky_z - p_W.z()) / r_W.z();
    const Vector3d at = p_W + s * r_W;
    const double F = f.reflectance + (1.0 - f.reflectance) * std::pow(1.0 - cos_i, 5);
    const float mirrored =
        sky_gain * sky.sample(static_cast<float>(at.x()), static_cast<float>(at.y()),
                              foot[k] * static_cast<float>((range + s) / range));
    value[k] += static_cast<float>(F) * (mirrored - value[k]);
  }
}

// The largest range along the rays [k0, k1) to what they hit so far [m]. Ranges are >= 0 (or
// infinite), so their bit patterns order like them: an integer maximum, which vectorises.
ALIGHT_SIMD_PASS float farthest_range(int k0, int k1, const float* __restrict th,
                                      const float* __restrict rlen) {
  int m = 0;
  for (int k = k0; k < k1; ++k) m = std::max(m, std::bit_cast<int>(th[k] * rlen[k]));
  return std::bit_cast<float>(m);
}

// Face coordinates, footprint and shade of the rays [k0, k1) that hit box `id` (the others are
// left as they are).
ALIGHT_SIMD_PASS void box_coords_pass(
    int k0, int k1, const float* __restrict rx, const float* __restrict ry,
    const float* __restrict rlen, const float* __restrict rscale, const float* __restrict th,
    const int* __restrict hb, const int* __restrict ha, const BoxFrame& f, int id,
    const float* lamp, const SurfaceTex& tex, float* __restrict tu, float* __restrict tv,
    float* __restrict fp, float* __restrict sh, float* __restrict tinv, float* __restrict tcols,
    float* __restrict trows, float* __restrict tmax, int* __restrict tid) {
  // This box's values for every ray of a chunk, then taken where it is the one hit.
  float cu[kMaxRun], cv[kMaxRun], cf[kMaxRun], cs[kMaxRun];
  const float M0 = f.M[0], M1 = f.M[1], M2 = f.M[2], M3 = f.M[3], M4 = f.M[4], M5 = f.M[5],
              M6 = f.M[6], M7 = f.M[7], M8 = f.M[8];
  const float o0 = f.o[0], o1 = f.o[1], o2 = f.o[2];
  const float L0 = f.lamp[0], L1 = f.lamp[1], L2 = f.lamp[2];
  const float r2 = lamp[3], la = lamp[4], lb = lamp[5];
  const float s0n = f.shade[0], s0p = f.shade[1], s1n = f.shade[2], s1p = f.shade[3],
              s2n = f.shade[4], s2p = f.shade[5];
  const float top_u0 = tex.top_u0, top_v0 = tex.top_v0;
  for (int c0 = k0; c0 < k1; c0 += kMaxRun) {
    const int c1 = std::min(k1, c0 + kMaxRun);
    for (int k = c0; k < c1; ++k) {
      const float t = th[k];
      const float d0 = M0 * rx[k] + M1 * ry[k] + M2;
      const float d1 = M3 * rx[k] + M4 * ry[k] + M5;
      const float d2 = M6 * rx[k] + M7 * ry[k] + M8;
      const float q0 = o0 + t * d0, q1 = o1 + t * d1, q2 = o2 + t * d2;
      // Weights of 0 or 1 per face axis and side instead of nested selects, which GCC 12 does
      // not vectorise; each sum below has a single non-zero term, so it is exact.
      const float wx = ha[k] == 0 ? 1.f : 0.f, wy = ha[k] == 1 ? 1.f : 0.f, wz = 1.f - wx - wy;
      const float d_axis = wx * d0 + wy * d1 + wz * d2;
      const float pos = d_axis < 0 ? 1.f : 0.f, neg = 1.f - pos;  // entering the + / - side
      // Face coordinates; each side face gets its own offset into the tile so faces differ.
      const float u = wx * (q1 + 1.7f) + wy * (q0 + 3.1f) + wz * (q0 + top_u0);
      const float v = wx * (q2 + pos * 0.9f + neg * 2.3f) + wy * (q2 + pos * 0.4f + neg * 1.3f) +
                      wz * (q1 + top_v0);
      const float cosi = std::max(0.05f, std::abs(d_axis) / rlen[k]);
      const float face_shade = wx * (pos * s0p + neg * s0n) + wy * (pos * s1p + neg * s1n) +
                               wz * (pos * s2p + neg * s2n);
      const float e0 = q0 - L0, e1 = q1 - L1, e2 = q2 - L2;
      const float shade = face_shade * (lb + la / (r2 + e0 * e0 + e1 * e1 + e2 * e2));
      const float foot = t * rscale[k] / std::sqrt(cosi);
      const int j = k - c0;
      cu[j] = u;
      cv[j] = v;
      cf[j] = foot;
      cs[j] = shade;
    }
    // Kept apart from the loop above, and blended as bits: with float selects on an integer
    // condition in it GCC 12 vectorises neither loop.
    auto blend = [](int mask, float a, float b) {
      return std::bit_cast<float>((std::bit_cast<int>(a) & mask) | (std::bit_cast<int>(b) & ~mask));
    };
    for (int k = c0; k < c1; ++k) {
      const int j = k - c0;
      const int mine = -static_cast<int>(hb[k] == id);
      tu[k] = blend(mine, cu[j], tu[k]);
      tv[k] = blend(mine, cv[j], tv[k]);
      fp[k] = blend(mine, cf[j], fp[k]);
      sh[k] = blend(mine, cs[j], sh[k]);
      tinv[k] = blend(mine, tex.inv_texel, tinv[k]);
      tcols[k] = blend(mine, tex.cols, tcols[k]);
      trows[k] = blend(mine, tex.rows, trows[k]);
      tmax[k] = blend(mine, tex.max_level, tmax[k]);
      tid[k] = (tex.id & mine) | (tid[k] & ~mine);
    }
  }
}

// Texture::sample() in three passes: where to read (SIMD), the reads (scalar), and the
// filtering (SIMD). Trilinear mip-mapping (Williams 1983): bilinear on level a, and where the
// footprint falls between two levels, blended with level b = a + 1 by w.
struct Taps {  // per ray
  std::vector<int> level, offset_a, dx_a, dy_a, offset_b, dx_b, dy_b;
  std::vector<float> w, fx_a, fy_a, fx_b, fy_b;
  // Texels 00, 01, 10, 11 of a level, one byte each from the lowest (converted in filter_pass):
  // one store a level instead of four, the stores being what bounds the reads' pass.
  std::vector<uint32_t> t_a, t_b;
  void resize(int n) {
    for (auto* v : {&level, &offset_a, &dx_a, &dy_a, &offset_b, &dx_b, &dy_b}) v->resize(n);
    for (auto* v : {&w, &fx_a, &fy_a, &fx_b, &fy_b}) v->resize(n);
    t_a.resize(n);
    t_b.resize(n);
  }
};

// 2^-l for an integer-valued l in [0, 126], exactly.
inline float exp2_neg(float l) { return std::bit_cast<float>((127 - static_cast<int>(l)) << 23); }

// Bilinear taps on a level `scale` = 2^-l times the size of level 0: the offset of texel 00 in
// the level's array, the steps to texel 01 and 10 (wrapping), and the weights.
inline void bilinear_taps(float x0, float y0, float scale, float cols0, float rows0, int& offset,
                          int& dx, int& dy, float& fx, float& fy) {
  const float x = x0 * scale - 0.5f, y = y0 * scale - 0.5f;
  int ix = static_cast<int>(x), iy = static_cast<int>(y);
  ix -= -static_cast<int>(x < static_cast<float>(ix)) & 1;  // floor without libm
  iy -= -static_cast<int>(y < static_cast<float>(iy)) & 1;
  fx = x - static_cast<float>(ix);
  fy = y - static_cast<float>(iy);
  const int cols = static_cast<int>(cols0 * scale), rows = static_cast<int>(rows0 * scale);
  const int xa = ix & (cols - 1), ya = iy & (rows - 1);
  const int xb = (xa + 1) & (cols - 1), yb = (ya + 1) & (rows - 1);
  // Row offsets by a float product (exact below 2^24 = 4096 x 4096): SSE2 has no 32-bit
  // integer multiply.
  const float cols_f = static_cast<float>(cols);
  offset = static_cast<int>(static_cast<float>(ya) * cols_f) + xa;
  dx = xb - xa;
  dy = static_cast<int>(static_cast<float>(yb - ya) * cols_f);
}

// (Restrict parameters of a function not inlined: GCC otherwise checks the aliasing of these
// arrays at run time, and gives up beyond ten pairs.)
ALIGHT_SIMD_PASS [[gnu::noinline]] void taps_pass(
    int count, const float* __restrict tu, const float* __restrict tv, const float* __restrict fp,
    const float* __restrict tinv, const float* __restrict tcols, const float* __restrict trows,
    const float* __restrict tmax, int* __restrict lv, float* __restrict w, int* __restrict oa,
    int* __restrict xa, int* __restrict ya, int* __restrict ob, int* __restrict xb,
    int* __restrict yb, float* __restrict fxa, float* __restrict fya, float* __restrict fxb,
    float* __restrict fyb) {
  for (int k = 0; k < count; ++k) {
    const float inv = tinv[k], max_level = tmax[k];
    const float level = Texture::fast_log2(fp[k] * inv);
    // Level a as Texture::sample() picks it; rays that see nothing may carry infinities: they
    // are read at level 0, texel 0, and their value discarded.
    const float clamped = std::min(std::max(level, 0.f), max_level);
    const float la = static_cast<float>(static_cast<int>(clamped));  // no truncf on SSE2
    const float between = ((level > 0.f) & (level < max_level)) ? 1.f : 0.f;
    w[k] = between * (level - la);
    const float lb = std::min(la + 1.f, max_level);
    float x0 = tu[k] * inv, y0 = tv[k] * inv;
    x0 = std::abs(x0) < 1e9f ? x0 : 0.f;
    y0 = std::abs(y0) < 1e9f ? y0 : 0.f;
    lv[k] = static_cast<int>(la);
    bilinear_taps(x0, y0, exp2_neg(la), tcols[k], trows[k], oa[k], xa[k], ya[k], fxa[k], fya[k]);
    bilinear_taps(x0, y0, exp2_neg(lb), tcols[k], trows[k], ob[k], xb[k], yb[k], fxb[k], fyb[k]);
  }
}

// The four texels at t (00), t + dx (01), t + dy (10) and t + dx + dy (11), packed as Taps keeps
// them. Neighbours along a row (dx = 1, all but the wrapping column) are read as one pair.
inline uint32_t texel_quad(const uint8_t* t, int dx, int dy) {
  static_assert(std::endian::native == std::endian::little, "a pair's first byte is its lowest");
  if (dx == 1) {
    uint16_t top, bottom;
    std::memcpy(&top, t, 2);
    std::memcpy(&bottom, t + dy, 2);
    return uint32_t(top) | uint32_t(bottom) << 16;
  }
  return uint32_t(t[0]) | uint32_t(t[dx]) << 8 | uint32_t(t[dy]) << 16 | uint32_t(t[dx + dy]) << 24;
}

// The texel reads: level a always, level b only where it is blended in.
[[gnu::noinline]] void fetch_pass(int count, const int* __restrict tid, const int* __restrict level,
                                  const uint8_t* const* __restrict levels, const int* __restrict oa,
                                  const int* __restrict xa, const int* __restrict ya,
                                  const int* __restrict ob, const int* __restrict xb,
                                  const int* __restrict yb, const float* __restrict w,
                                  uint32_t* __restrict ta, uint32_t* __restrict tb) {
  for (int k = 0; k < count; ++k) {
    const uint8_t* const* lv = levels + tid[k] * kMaxLevels + level[k];
    ta[k] = texel_quad(lv[0] + oa[k], xa[k], ya[k]);
    tb[k] = w[k] != 0.f ? texel_quad(lv[1] + ob[k], xb[k], yb[k]) : 0u;
  }
}

// Filtered, shaded values; kBackground where nothing was hit. (Not inlined: see taps_pass.)
ALIGHT_SIMD_PASS [[gnu::noinline]] void filter_pass(int count, const Taps& taps,
                                                    const float* __restrict th,
                                                    const float* __restrict sh, float background,
                                                    float* __restrict value) {
  const uint32_t* __restrict texels_a = taps.t_a.data();
  const uint32_t* __restrict texels_b = taps.t_b.data();
  const float* __restrict fxa = taps.fx_a.data();
  const float* __restrict fya = taps.fy_a.data();
  const float* __restrict fxb = taps.fx_b.data();
  const float* __restrict fyb = taps.fy_b.data();
  const float* __restrict w = taps.w.data();
  const float inf = std::numeric_limits<float>::infinity();
  for (int k = 0; k < count; ++k) {
    const uint32_t a = texels_a[k], b = texels_b[k];
    const float p00 = static_cast<float>(static_cast<int>(a & 0xff));
    const float p01 = static_cast<float>(static_cast<int>((a >> 8) & 0xff));
    const float p10 = static_cast<float>(static_cast<int>((a >> 16) & 0xff));
    const float p11 = static_cast<float>(static_cast<int>(a >> 24));
    const float q00 = static_cast<float>(static_cast<int>(b & 0xff));
    const float q01 = static_cast<float>(static_cast<int>((b >> 8) & 0xff));
    const float q10 = static_cast<float>(static_cast<int>((b >> 16) & 0xff));
    const float q11 = static_cast<float>(static_cast<int>(b >> 24));
    const float ta = p00 + fxa[k] * (p01 - p00);
    const float ba = p10 + fxa[k] * (p11 - p10);
    const float A = ta + fya[k] * (ba - ta);
    const float tb = q00 + fxb[k] * (q01 - q00);
    const float bb = q10 + fxb[k] * (q11 - q10);
    const float B = tb + fyb[k] * (bb - tb);
    const float v = (A + w[k] * (B - A)) * sh[k];
    value[k] = th[k] < inf ? v : background;
  }
}
}  // namespace

Renderer::Renderer(const CameraModel& model, int supersample) : model_(model), ss_(supersample) {
  assert(ss_ >= 1);
  const int W = model.width, H = model.height, n = ss_ * ss_;
  ray_x_.resize(static_cast<size_t>(W) * H * n);
  ray_y_.resize(ray_x_.size());
  ray_scale_.resize(ray_x_.size());
  ray_len_.resize(ray_x_.size());
  tiles_x_ = (W + kTile - 1) / kTile;
  tiles_y_ = (H + kTile - 1) / kTile;
  const float inf = std::numeric_limits<float>::infinity();
  tile_bounds_.assign(static_cast<size_t>(tiles_x_) * tiles_y_, cv::Vec4f(inf, inf, -inf, -inf));
  for (int v = 0; v < H; ++v) {
    for (int u = 0; u < W; ++u) {
      // The pixel's footprint at unit depth from the spacing of neighbouring rays, so the mip
      // level also follows the lens distortion.
      const Vector3d r0 = model.ray(Vector2d(u, v));
      const double sx = (model.ray(Vector2d(u + 1, v)) - r0).norm();
      const double sy = (model.ray(Vector2d(u, v + 1)) - r0).norm();
      const float scale = static_cast<float>(std::sqrt(sx * sy) / ss_);
      cv::Vec4f& b = tile_bounds_[(v / kTile) * tiles_x_ + u / kTile];
      for (int j = 0; j < ss_; ++j) {
        for (int i = 0; i < ss_; ++i) {
          const Vector2d px(u + (i + 0.5) / ss_ - 0.5, v + (j + 0.5) / ss_ - 0.5);
          const Vector3d r = ss_ == 1 ? r0 : model.ray(px);
          const size_t k = (static_cast<size_t>(v) * W + u) * n + j * ss_ + i;
          ray_x_[k] = static_cast<float>(r.x());
          ray_y_[k] = static_cast<float>(r.y());
          ray_len_[k] = static_cast<float>(r.norm());
          ray_scale_[k] = scale * ray_len_[k];
          b[0] = std::min(b[0], ray_x_[k]);
          b[1] = std::min(b[1], ray_y_[k]);
          b[2] = std::max(b[2], ray_x_[k]);
          b[3] = std::max(b[3], ray_y_[k]);
        }
      }
    }
  }
}

cv::Mat Renderer::render(const Scene& scene, const Isometry3d& X_WC, float gain) const {
  cv::Mat acc(model_.height, model_.width, CV_32F);
  acc.setTo(0);
  accumulate(scene, X_WC, gain, acc);
  cv::Mat out;
  acc.convertTo(out, CV_8U);
  return out;
}

void Renderer::accumulate(const Scene& scene, const Isometry3d& X_WC, float weight,
                          cv::Mat& acc) const {
  assert(acc.type() == CV_32F && acc.rows == model_.height && acc.cols == model_.width);
  if (threads_ <= 1) {
    render_rows(scene, X_WC, weight, 0, model_.height, acc.ptr<float>(), acc.step1());
    return;
  }
  cv::parallel_for_(
      cv::Range(0, model_.height),
      [&](const cv::Range& r) {
        render_rows(scene, X_WC, weight, r.start, r.end, acc.ptr<float>(), acc.step1());
      },
      threads_ * 4);
}

void Renderer::accumulate_rows(const Scene& scene, const Isometry3d& X_WC, float weight, int row0,
                               int row1, cv::Mat& acc) const {
  assert(acc.type() == CV_32F && acc.rows == model_.height && acc.cols == model_.width);
  assert(0 <= row0 && row0 <= row1 && row1 <= model_.height);
  if (row0 < row1) render_rows(scene, X_WC, weight, row0, row1, acc.ptr<float>(), acc.step1());
}

void Renderer::render_rows(const Scene& scene, const Isometry3d& X_WC, float weight, int row0,
                           int row1, float* out, size_t out_step) const {
  const int W = model_.width, n = ss_ * ss_;
  const Matrix3d R_WC = X_WC.linear();
  const Vector3d C_W = X_WC.translation();
  const Vector3d light = scene.lighting.light_dir_W.normalized();
  auto shade_of = [&](const Vector3d& n_W) {
    return static_cast<float>(
        scene.lighting.gain *
        (scene.lighting.ambient + scene.lighting.diffuse * std::max(0.0, n_W.dot(light))));
  };
  // In a cast shadow a surface keeps the ambient share of its shade (1: it faces away).
  auto shadowed_of = [&](const Vector3d& n_W) {
    const double lit =
        scene.lighting.ambient + scene.lighting.diffuse * std::max(0.0, n_W.dot(light));
    return lit > 0 ? static_cast<float>(scene.lighting.ambient / lit) : 1.f;
  };

  // Per-frame preparation: world->camera, boxes in camera terms, and which tiles each box may
  // cover (a bit per box; the scenes hold a handful of boxes).
  const float Rw[9] = {float(R_WC(0, 0)), float(R_WC(0, 1)), float(R_WC(0, 2)),
                       float(R_WC(1, 0)), float(R_WC(1, 1)), float(R_WC(1, 2)),
                       float(R_WC(2, 0)), float(R_WC(2, 1)), float(R_WC(2, 2))};
  const float Cz = static_cast<float>(C_W.z());
  const float Cx = static_cast<float>(C_W.x()), Cy = static_cast<float>(C_W.y());
  const float floor_shade = shade_of(Vector3d::UnitZ());
  // The lamp's falloff (Scene::illumination) as lamp_b + lamp_a / (r^2 + d^2).
  const LightingParams& lit = scene.lighting;
  const float lamp_r2 = static_cast<float>(lit.lamp_radius_m * lit.lamp_radius_m);
  const float lamp_a =
      static_cast<float>(2.0 * lit.falloff * lit.lamp_radius_m * lit.lamp_radius_m);
  const float lamp_b = static_cast<float>(1.0 - lit.falloff);
  const float lamp[6] = {static_cast<float>(lit.lamp_W.x()),
                         static_cast<float>(lit.lamp_W.y()),
                         static_cast<float>(lit.lamp_W.z() * lit.lamp_W.z()),
                         lamp_r2,
                         lamp_a,
                         lamp_b};

  assert(scene.boxes.size() <= 32);
  std::vector<BoxFrame> boxes(scene.boxes.size());
  const Matrix3d R_CW = R_WC.transpose();
  for (size_t bi = 0; bi < scene.boxes.size(); ++bi) {
    const Box& b = scene.boxes[bi];
    const Matrix3d R_WO = b.R_WO();
    const Matrix3d M = R_WO.transpose() * R_WC;
    const Vector3d o = R_WO.transpose() * (C_W - b.center_W);
    BoxFrame& f = boxes[bi];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) f.M[r * 3 + c] = static_cast<float>(M(r, c));
    for (int a = 0; a < 3; ++a) {
      f.o[a] = static_cast<float>(o[a]);
      f.h[a] = static_cast<float>(b.half_size_m[a]);
      f.shade[a * 2 + 0] = shade_of(-R_WO.col(a));
      f.shade[a * 2 + 1] = shade_of(R_WO.col(a));
      f.shadowed[a * 2 + 0] = shadowed_of(-R_WO.col(a));
      f.shadowed[a * 2 + 1] = shadowed_of(R_WO.col(a));
    }
    const Vector3d lamp_O = R_WO.transpose() * (lit.lamp_W - b.center_W);
    for (int a = 0; a < 3; ++a) f.lamp[a] = static_cast<float>(lamp_O[a]);
    f.near_range = static_cast<float>((o.cwiseAbs() - b.half_size_m).cwiseMax(0.0).norm());
    f.texture = b.texture;
    f.reflectance = scene.sky_texture >= 0 ? static_cast<float>(b.reflectance) : 0.f;
    f.up_W = R_WO.col(2);
    // Cull: bounds of the projected corners on the z = 1 plane.
    bool behind_all = true;
    f.straddles = false;
    f.x0 = f.y0 = 1e30f;
    f.x1 = f.y1 = -1e30f;
    std::vector<cv::Point2f> projected;
    for (int k = 0; k < 8; ++k) {
      const Vector3d corner_O((k & 1 ? 1 : -1) * b.half_size_m.x(),
                              (k & 2 ? 1 : -1) * b.half_size_m.y(),
                              (k & 4 ? 1 : -1) * b.half_size_m.z());
      const Vector3d p_C = R_CW * (b.center_W + R_WO * corner_O - C_W);
      if (p_C.z() > kNear) {
        behind_all = false;
        f.x0 = std::min(f.x0, float(p_C.x() / p_C.z()));
        f.x1 = std::max(f.x1, float(p_C.x() / p_C.z()));
        f.y0 = std::min(f.y0, float(p_C.y() / p_C.z()));
        f.y1 = std::max(f.y1, float(p_C.y() / p_C.z()));
        projected.emplace_back(float(p_C.x() / p_C.z()), float(p_C.y() / p_C.z()));
      } else {
        f.straddles = true;
      }
    }
    f.visible = !behind_all;
    if (f.visible && !f.straddles) cv::convexHull(projected, f.hull, /*clockwise=*/false);
  }
  std::vector<Occluder> occluders;
  if (scene.lighting.shadows) {
    auto add = [&](const Box& b) {
      const Matrix3d R_OW = b.R_WO().transpose();
      occluders.push_back({R_OW, b.center_W, b.half_size_m, R_OW * light});
    };
    for (const Box& b : scene.boxes) add(b);
    for (const Box& b : scene.shadow_casters) add(b);
  }
  const float floor_shadowed = shadowed_of(Vector3d::UnitZ());
  const bool mirrors = std::any_of(boxes.begin(), boxes.end(),
                                   [](const BoxFrame& f) { return f.reflectance > 0.f; });
  // Nearest first, so a pixel stops testing boxes once its hit is nearer than the next box.
  std::sort(boxes.begin(), boxes.end(),
            [](const BoxFrame& a, const BoxFrame& b) { return a.near_range < b.near_range; });
  std::vector<uint32_t> tile_mask(static_cast<size_t>(tiles_x_) * tiles_y_, 0u);
  for (size_t bi = 0; bi < boxes.size(); ++bi) {
    const BoxFrame& f = boxes[bi];
    if (!f.visible) continue;
    const uint32_t bit = 1u << bi;
    float orientation = 0.f;  // sign of the hull's winding
    if (f.hull.size() >= 3) {
      const cv::Point2f a = f.hull[1] - f.hull[0], b = f.hull[2] - f.hull[1];
      orientation = a.x * b.y - a.y * b.x > 0 ? 1.f : -1.f;
    }
    for (size_t t = 0; t < tile_mask.size(); ++t) {
      const cv::Vec4f& tb = tile_bounds_[t];
      if (f.straddles) {
        tile_mask[t] |= bit;
      } else if (tb[2] >= f.x0 && tb[0] <= f.x1 && tb[3] >= f.y0 && tb[1] <= f.y1) {
        if (f.hull.size() < 3 || rect_meets_hull(tb, f.hull, orientation)) tile_mask[t] |= bit;
      }
    }
  }

  // Each row is rendered in passes over its rays, each a plain loop over arrays that the compiler
  // turns into SIMD code: the floor's intersection for every ray, each box's slab test on the
  // tiles it may cover, the surface coordinates and footprint; only the texture fetches stay
  // scalar. Deciding per pixel which surface it sees, in one loop, branched and serialised too
  // much for that.
  const int N = W * n;  // rays in a row
  std::vector<float> t_hit(N), tex_u(N), tex_v(N), foot(N), shade(N), value(N);
  std::vector<float> tex_inv(N), tex_cols(N), tex_rows(N), tex_max(N);
  std::vector<int> hit_box(N), hit_axis(N), tex_id(N);
  Taps taps;
  taps.resize(N);
  // Each texture's levels as arrays (kMaxLevels slots per texture), and its parameters.
  std::vector<const uint8_t*> levels(scene.textures.size() * kMaxLevels, nullptr);
  std::vector<SurfaceTex> surface_tex(scene.textures.size());
  for (size_t i = 0; i < scene.textures.size(); ++i) {
    const Texture& tex = scene.textures[i];
    assert(tex.n_levels() <= kMaxLevels);
    for (int l = 0; l < tex.n_levels(); ++l) {
      assert(tex.level(l).isContinuous());
      levels[i * kMaxLevels + l] = tex.level(l).ptr<uint8_t>();
    }
    const float cols = static_cast<float>(tex.level(0).cols),
                rows = static_cast<float>(tex.level(0).rows);
    const float centred = tex.has_seams() ? 0.5f : 0.f;
    surface_tex[i] = SurfaceTex{tex.inv_texel_m(),
                                cols,
                                rows,
                                static_cast<float>(tex.n_levels() - 1),
                                static_cast<int>(i),
                                centred * cols / tex.inv_texel_m(),
                                centred * rows / tex.inv_texel_m()};
  }
  // Per row and box: the rays [first, second) it was hit on, when tested.
  std::vector<std::pair<int, int>> box_span(boxes.size());
  const float inv_n = weight / static_cast<float>(n);
  for (int v = row0; v < row1; ++v) {
    const size_t base = static_cast<size_t>(v) * N;
    const float* __restrict rx = ray_x_.data() + base;
    const float* __restrict ry = ray_y_.data() + base;
    const float* __restrict rlen = ray_len_.data() + base;
    const float* __restrict rscale = ray_scale_.data() + base;
    float* __restrict th = t_hit.data();
    int* __restrict hb = hit_box.data();
    int* __restrict ha = hit_axis.data();

    floor_pass(N, rx, ry, Rw, Cz, th, hb, ha);

    // Boxes, nearest first, on the tiles of this row that they may cover, consecutive tiles in
    // one run (each call sets up its constants: per tile that cost as much as the tests).
    const uint32_t* masks = &tile_mask[(v / kTile) * tiles_x_];
    for (size_t bi = 0; bi < boxes.size(); ++bi) {
      const BoxFrame& f = boxes[bi];
      const uint32_t bit = 1u << bi;
      box_span[bi] = {N, 0};
      int run0 = -1;  // first ray of the open run
      for (int tx = 0; tx <= tiles_x_; ++tx) {
        const int k0 = tx * kTile * n, k1 = std::min(W, (tx + 1) * kTile) * n;
        // A tile whose every ray already sees something nearer than any point of this box (and
        // so of every later box: they are sorted by that bound) is skipped.
        const bool test =
            tx < tiles_x_ && (masks[tx] & bit) && f.near_range <= farthest_range(k0, k1, th, rlen);
        if (test && run0 < 0) run0 = k0;
        if (!test && run0 >= 0) {
          if (box_pass(run0, k0, rx, ry, f.M, f.o, f.h, static_cast<int>(bi), th, hb, ha)) {
            box_span[bi].first = std::min(box_span[bi].first, run0);
            box_span[bi].second = std::max(box_span[bi].second, k0);
          }
          run0 = -1;
        }
      }
    }

    // Surface coordinates, footprint and shade as if on the floor for every ray...
    floor_coords_pass(N, rx, ry, rlen, rscale, th, Rw, Cx, Cy, floor_shade, lamp,
                      surface_tex[scene.floor_texture], tex_u.data(), tex_v.data(), foot.data(),
                      shade.data(), tex_inv.data(), tex_cols.data(), tex_rows.data(),
                      tex_max.data(), tex_id.data());
    // ...then, on the tiles each box was tested on, the rays that hit it instead.
    for (int bi = 0; bi < static_cast<int>(boxes.size()); ++bi) {
      // Only the span of rays still seeing this box after all were tested.
      auto [k0, k1] = box_span[bi];
      while (k0 < k1 && hb[k0] != bi) ++k0;
      while (k1 > k0 && hb[k1 - 1] != bi) --k1;
      if (k0 >= k1) continue;
      box_coords_pass(k0, k1, rx, ry, rlen, rscale, th, hb, ha, boxes[bi], bi, lamp,
                      surface_tex[boxes[bi].texture], tex_u.data(), tex_v.data(), foot.data(),
                      shade.data(), tex_inv.data(), tex_cols.data(), tex_rows.data(),
                      tex_max.data(), tex_id.data());
    }

    if (!occluders.empty())
      shadow_pass(N, rx, ry, th, hb, ha, R_WC, C_W, boxes, floor_shadowed, occluders, shade.data());

    taps_pass(N, tex_u.data(), tex_v.data(), foot.data(), tex_inv.data(), tex_cols.data(),
              tex_rows.data(), tex_max.data(), taps.level.data(), taps.w.data(),
              taps.offset_a.data(), taps.dx_a.data(), taps.dy_a.data(), taps.offset_b.data(),
              taps.dx_b.data(), taps.dy_b.data(), taps.fx_a.data(), taps.fy_a.data(),
              taps.fx_b.data(), taps.fy_b.data());
    fetch_pass(N, tex_id.data(), taps.level.data(), levels.data(), taps.offset_a.data(),
               taps.dx_a.data(), taps.dy_a.data(), taps.offset_b.data(), taps.dx_b.data(),
               taps.dy_b.data(), taps.w.data(), taps.t_a.data(), taps.t_b.data());
    filter_pass(N, taps, th, shade.data(), kBackground, value.data());
    if (mirrors)
      reflection_pass(N, rx, ry, th, hb, ha, foot.data(), R_WC, C_W, boxes,
                      scene.textures[scene.sky_texture], scene.sky_z_m,
                      static_cast<float>(scene.lighting.gain), value.data());
    float* __restrict row = out + static_cast<size_t>(v) * out_step;
    if (n == 1) {  // the common case, as SIMD code
      for (int u = 0; u < W; ++u) row[u] += value[u] * inv_n;
    } else {
      for (int u = 0; u < W; ++u) {
        float sum = 0.f;
        for (int s = 0; s < n; ++s) sum += value[u * n + s];
        row[u] += sum * inv_n;
      }
    }
  }
}

}  // namespace alight::sim
