#include "sim/texture.hpp"

#include <cassert>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

namespace alight::sim {

namespace {

int floor_pow2(int n) {
  int p = 1;
  while (p * 2 <= n) p *= 2;
  return p;
}

// Smooth random field with period `n` texels whose features are `cell` texels: a random grid
// upsampled bicubically with wrapped borders (value noise).
cv::Mat wrapped_value_noise(int n, int cell, std::mt19937_64& rng) {
  const int m = std::max(2, n / std::max(1, cell));
  cv::Mat grid(m, m, CV_32F);
  std::normal_distribution<float> g(0.f, 1.f);
  for (int y = 0; y < m; ++y)
    for (int x = 0; x < m; ++x) grid.at<float>(y, x) = g(rng);
  if (m == n) return grid;
  const int pad = 3;
  cv::Mat padded;
  cv::copyMakeBorder(grid, padded, pad, pad, pad, pad, cv::BORDER_WRAP);
  const double s = static_cast<double>(n) / m;
  cv::Mat big;
  cv::resize(padded, big, cv::Size(), s, s, cv::INTER_CUBIC);
  const int off = static_cast<int>(std::lround(pad * s));
  return big(cv::Rect(off, off, n, n)).clone();
}

// Draws `fn` at the position and at its wrapped copies so the tile stays seamless.
template <class F>
void draw_wrapped(int n, cv::Point2f c, float r, F fn) {
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const cv::Point2f p(c.x + dx * n, c.y + dy * n);
      if (p.x + r < 0 || p.y + r < 0 || p.x - r > n || p.y - r > n) continue;
      fn(p);
    }
}

cv::Mat normalise(const cv::Mat& f, double mean, double contrast, double target_sigma = 50.0) {
  cv::Scalar mu, sd;
  cv::meanStdDev(f, mu, sd);
  cv::Mat out;
  const double k = sd[0] > 1e-9 ? contrast * target_sigma / sd[0] : 0.0;
  f.convertTo(out, CV_8U, k, mean - k * mu[0]);
  return out;
}

cv::Mat noise_texture(const TextureSpec& s, std::mt19937_64& rng) {
  const int n = s.size_px;
  const int feature = std::max(2, static_cast<int>(s.feature_m / s.texel_m));
  cv::Mat acc = cv::Mat::zeros(n, n, CV_32F);
  // Octaves from 4x the feature size down to 2 texels, amplitude falling with frequency so the
  // pattern has structure at every distance the camera sees it from (pink-ish spectrum).
  for (int cell = std::min(n / 2, feature * 2); cell >= 2; cell /= 2) {
    acc += wrapped_value_noise(n, cell, rng) * std::pow(static_cast<double>(cell), 0.3);
  }
  return normalise(acc, s.mean, s.contrast);
}

cv::Mat blob_texture(const TextureSpec& s, std::mt19937_64& rng) {
  const int n = s.size_px;
  const float r_mean = static_cast<float>(s.feature_m / s.texel_m);
  cv::Mat img(n, n, CV_32F, cv::Scalar(s.mean));
  std::uniform_real_distribution<float> pos(0.f, static_cast<float>(n));
  std::uniform_real_distribution<float> rad(0.3f * r_mean, 1.6f * r_mean);
  std::uniform_real_distribution<float> grey(-110.f, 110.f);
  const int count = static_cast<int>(1.2 * n * n / (M_PI * r_mean * r_mean)) + 8;
  for (int i = 0; i < count; ++i) {
    const cv::Point2f c(pos(rng), pos(rng));
    const float r = std::max(1.0f, rad(rng));
    const float g = static_cast<float>(s.mean) + grey(rng) * static_cast<float>(s.contrast);
    draw_wrapped(n, c, r, [&](cv::Point2f p) {
      cv::circle(img, cv::Point(cvRound(p.x * 16), cvRound(p.y * 16)), cvRound(r * 16),
                 cv::Scalar(g), cv::FILLED, cv::LINE_AA, 4);
    });
  }
  // Fine grain so a close-up still has texture between the blobs.
  img += wrapped_value_noise(n, 2, rng) * (6.0 * s.contrast);
  cv::Mat out;
  img.convertTo(out, CV_8U);
  return out;
}

cv::Mat paper_texture(const TextureSpec& s, std::mt19937_64& rng) {
  // A printed page: light paper, lines of dark "words" of character-sized marks, paragraph gaps.
  const int n = s.size_px;
  const float line_h = std::max(3.f, static_cast<float>(s.feature_m / s.texel_m));
  cv::Mat img(n, n, CV_32F, cv::Scalar(s.mean));
  img += wrapped_value_noise(n, 8, rng) * (4.0 * s.contrast);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  const float ink = static_cast<float>(s.mean) - 150.f * static_cast<float>(s.contrast);
  const float char_w = 0.55f * line_h;
  for (float y = 0.5f * line_h; y + line_h < n; y += 1.6f * line_h) {
    if (u(rng) < 0.12f) continue;  // paragraph break
    float x = line_h * (1.f + 2.f * u(rng));
    const float end = n - line_h * (1.f + 4.f * u(rng));
    while (x < end) {
      const int letters = 1 + static_cast<int>(9 * u(rng));
      for (int k = 0; k < letters && x < end; ++k) {
        const float h = line_h * (u(rng) < 0.3f ? 0.95f : 0.62f);
        const float w = char_w * (0.5f + 0.6f * u(rng));
        const float y0 = y + (line_h - h);
        cv::rectangle(img, cv::Point(cvRound(x * 16), cvRound(y0 * 16)),
                      cv::Point(cvRound((x + w) * 16), cvRound((y + line_h) * 16)),
                      cv::Scalar(ink + 40.f * u(rng)), cv::FILLED, cv::LINE_AA, 4);
        x += w + 0.25f * char_w;
      }
      x += char_w * 1.2f;
    }
  }
  cv::Mat out;
  img.convertTo(out, CV_8U);
  return out;
}

cv::Mat checker_texture(const TextureSpec& s, std::mt19937_64& rng) {
  // Squares of random grey: strong corners at known places (renderer geometry tests).
  const int n = s.size_px;
  const int cell = std::max(2, static_cast<int>(s.feature_m / s.texel_m));
  cv::Mat img(n, n, CV_8U);
  std::uniform_int_distribution<int> g(-100, 100);
  const int cells = (n + cell - 1) / cell;
  std::vector<int> level(static_cast<size_t>(cells * cells));
  for (auto& l : level) l = cv::saturate_cast<uchar>(s.mean + s.contrast * g(rng));
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      img.at<uchar>(y, x) = static_cast<uchar>(level[(y / cell) * cells + x / cell]);
  return img;
}

cv::Mat tiles_texture(const TextureSpec& s, std::mt19937_64& rng) {
  // A floor of square tiles of side feature_m, each one flat grey, with darker grout between:
  // a surface whose only features are the tiles' edges and corners. The
  // tile side is rounded so a whole number of tiles fills the wrapping texture.
  const int n = s.size_px;
  const int tiles = std::max(1, static_cast<int>(std::lround(n * s.texel_m / s.feature_m)));
  const double cell = static_cast<double>(n) / tiles;
  const double grout = std::max(1.0, 0.02 * cell);
  std::normal_distribution<float> tone(0.f, 6.f * static_cast<float>(s.contrast));
  std::vector<float> level(static_cast<size_t>(tiles * tiles));
  for (auto& l : level) l = static_cast<float>(s.mean) + tone(rng);
  const float grout_level = static_cast<float>(s.mean) - 45.f * static_cast<float>(s.contrast);
  cv::Mat img(n, n, CV_32F);
  for (int y = 0; y < n; ++y) {
    const int ty = static_cast<int>(y / cell);
    const bool gy = y - ty * cell < grout;
    for (int x = 0; x < n; ++x) {
      const int tx = static_cast<int>(x / cell);
      const bool gx = x - tx * cell < grout;
      img.at<float>(y, x) = (gx || gy) ? grout_level : level[static_cast<size_t>(ty * tiles + tx)];
    }
  }
  // A faint glaze: far too weak for features away from the grout, as on a real tiled floor.
  img += wrapped_value_noise(n, 4, rng) * (1.5 * s.contrast);
  cv::Mat out;
  img.convertTo(out, CV_8U);
  return out;
}

}  // namespace

cv::Mat make_procedural_texture(const TextureSpec& spec, uint64_t seed) {
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ULL + static_cast<uint64_t>(spec.seed) * 7919 + 1);
  if (spec.kind == "noise") return noise_texture(spec, rng);
  if (spec.kind == "blobs") return blob_texture(spec, rng);
  if (spec.kind == "paper") return paper_texture(spec, rng);
  if (spec.kind == "checker") return checker_texture(spec, rng);
  if (spec.kind == "tiles") return tiles_texture(spec, rng);
  assert(false && "validate() admits only known kinds");
  return {};
}

Texture Texture::make(const TextureSpec& spec, uint64_t seed) {
  if (spec.kind == "image") {
    assert(!spec.image.empty());
    return from_image(spec.image, spec.texel_m);
  }
  Texture t;
  t.inv_texel_m_ = static_cast<float>(1.0 / spec.texel_m);
  t.build_pyramid(make_procedural_texture(spec, seed));
  return t;
}

Texture Texture::from_image(const cv::Mat& mono8, double texel_m) {
  assert(mono8.type() == CV_8UC1 && !mono8.empty());
  Texture t;
  t.inv_texel_m_ = static_cast<float>(1.0 / texel_m);
  t.has_seams_ = true;
  // Wrapping by bit masks needs power-of-two sides; the image is scaled to the nearest below
  // (at most 4096) and its texel size applies to the scaled pixels.
  const int w = std::min(4096, floor_pow2(mono8.cols)), h = std::min(4096, floor_pow2(mono8.rows));
  cv::Mat scaled;
  if (w != mono8.cols || h != mono8.rows)
    cv::resize(mono8, scaled, cv::Size(w, h), 0, 0, cv::INTER_AREA);
  else
    scaled = mono8;
  t.build_pyramid(scaled);
  return t;
}

void Texture::build_pyramid(const cv::Mat& base) {
  levels_.clear();
  cv::Mat cur = base;
  while (true) {
    Level L;
    L.pixels = cur.isContinuous() ? cur : cur.clone();  // the renderer indexes it as one array
    L.mask_x = cur.cols - 1;
    L.mask_y = cur.rows - 1;
    levels_.push_back(L);
    if (cur.cols < 2 || cur.rows < 2) break;
    // A 2x2 box average per level: the classic mip-map prefilter; exact for power-of-two sides.
    cv::Mat next;
    cv::resize(cur, next, cv::Size(cur.cols / 2, cur.rows / 2), 0, 0, cv::INTER_AREA);
    cur = next;
  }
}

}  // namespace alight::sim
