#include "sim/renderer.hpp"

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace alight::sim {

namespace {
constexpr int kTile = 16;
constexpr float kNear = 1e-3f;  // [m] along the optical axis

struct BoxFrame {  // one box, prepared for one frame
  float M[9];      // camera direction -> box frame
  float o[3];      // camera centre in the box frame
  float h[3];      // half sizes
  float shade[6];  // per face: axis * 2 + (positive side)
  float lamp[3];   // the lamp in the box frame
  float near_range;  // no point of the box is closer to the camera [m]
  const Texture* tex;
  bool visible;
  bool straddles;    // has corners behind the camera: may cover any tile
  float x0, y0, x1, y1;  // bounds of its projection on the z = 1 plane
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

void Renderer::render_rows(const Scene& scene, const Isometry3d& X_WC, float weight, int row0,
                           int row1, float* out, size_t out_step) const {
  const int W = model_.width, n = ss_ * ss_;
  const Matrix3d R_WC = X_WC.linear();
  const Vector3d C_W = X_WC.translation();
  const Vector3d light = scene.lighting.light_dir_W.normalized();
  auto shade_of = [&](const Vector3d& n_W) {
    return static_cast<float>(scene.lighting.gain *
                              (scene.lighting.ambient + scene.lighting.diffuse * std::max(0.0, n_W.dot(light))));
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
  const bool lamp_on = lit.falloff > 0;
  const float lamp_r2 = static_cast<float>(lit.lamp_radius_m * lit.lamp_radius_m);
  const float lamp_a = static_cast<float>(2.0 * lit.falloff * lit.lamp_radius_m * lit.lamp_radius_m);
  const float lamp_b = static_cast<float>(1.0 - lit.falloff);
  const float Lx = static_cast<float>(lit.lamp_W.x()), Ly = static_cast<float>(lit.lamp_W.y());
  const float Lz2 = static_cast<float>(lit.lamp_W.z() * lit.lamp_W.z());
  const Texture& floor_tex = scene.textures[scene.floor_texture];

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
    }
    const Vector3d lamp_O = R_WO.transpose() * (lit.lamp_W - b.center_W);
    for (int a = 0; a < 3; ++a) f.lamp[a] = static_cast<float>(lamp_O[a]);
    f.near_range = static_cast<float>((o.cwiseAbs() - b.half_size_m).cwiseMax(0.0).norm());
    f.tex = &scene.textures[b.texture];
    // Cull: bounds of the projected corners on the z = 1 plane.
    bool behind_all = true;
    f.straddles = false;
    f.x0 = f.y0 = 1e30f;
    f.x1 = f.y1 = -1e30f;
    std::vector<cv::Point2f> projected;
    for (int k = 0; k < 8; ++k) {
      const Vector3d corner_O((k & 1 ? 1 : -1) * b.half_size_m.x(), (k & 2 ? 1 : -1) * b.half_size_m.y(),
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

  const float inv_n = weight / static_cast<float>(n);
  for (int v = row0; v < row1; ++v) {
    float* row = out + static_cast<size_t>(v) * out_step;
    const uint32_t* masks = &tile_mask[(v / kTile) * tiles_x_];
    for (int u = 0; u < W; ++u) {
      const uint32_t mask = masks[u / kTile];
      float sum = 0.f;
      for (int s = 0; s < n; ++s) {
        const size_t k = (static_cast<size_t>(v) * W + u) * n + s;
        const float dx = ray_x_[k], dy = ray_y_[k];
        const float dlen = ray_len_[k];
        float best_t = std::numeric_limits<float>::infinity();
        float value = kBackground;
        // Floor (z = 0), seen from above.
        const float dwz = Rw[6] * dx + Rw[7] * dy + Rw[8];
        if (dwz < -1e-6f && Cz > 0.f) {
          best_t = -Cz / dwz;
        }
        int hit_box = -1, hit_axis = 0;
        float hq[3] = {0, 0, 0};
        float hit_d_axis = 0.f;
        for (uint32_t m = mask; m; m &= m - 1) {
          const int bi = __builtin_ctz(m);
          const BoxFrame& f = boxes[bi];
          if (f.near_range > best_t * dlen) break;  // this and all later boxes are farther
          // A component of exactly zero would turn the shared reciprocal below into NaN.
          auto nonzero = [](float d) { return std::abs(d) < 1e-12f ? 1e-12f : d; };
          const float d0 = nonzero(f.M[0] * dx + f.M[1] * dy + f.M[2]);
          const float d1 = nonzero(f.M[3] * dx + f.M[4] * dy + f.M[5]);
          const float d2 = nonzero(f.M[6] * dx + f.M[7] * dy + f.M[8]);
          const float dl[3] = {d0, d1, d2};
          float tmin = -std::numeric_limits<float>::infinity();
          float tmax = std::numeric_limits<float>::infinity();
          int axis = 0;
          // One division for the three reciprocals (1/d0 = d1 d2 / (d0 d1 d2), ...).
          const float p01 = d0 * d1, inv_all = 1.f / (p01 * d2);
          const float invs[3] = {d1 * d2 * inv_all, d0 * d2 * inv_all, p01 * inv_all};
          for (int a = 0; a < 3; ++a) {
            const float inv = invs[a];
            float ta = (-f.h[a] - f.o[a]) * inv, tb = (f.h[a] - f.o[a]) * inv;
            if (ta > tb) std::swap(ta, tb);
            if (ta > tmin) {
              tmin = ta;
              axis = a;
            }
            tmax = std::min(tmax, tb);
          }
          if (tmin <= tmax && tmin > kNear && tmin < best_t) {
            best_t = tmin;
            hit_box = bi;
            hit_axis = axis;
            hit_d_axis = dl[axis];
            hq[0] = f.o[0] + tmin * d0;
            hq[1] = f.o[1] + tmin * d1;
            hq[2] = f.o[2] + tmin * d2;
          }
        }
        if (hit_box >= 0) {
          const BoxFrame& f = boxes[hit_box];
          // Face coordinates; each face gets its own offset into the tile so faces differ.
          float tu, tv;
          if (hit_axis == 2) {
            tu = hq[0];
            tv = hq[1];
          } else if (hit_axis == 0) {
            tu = hq[1] + 1.7f;
            tv = hq[2] + (hit_d_axis < 0 ? 0.9f : 2.3f);
          } else {
            tu = hq[0] + 3.1f;
            tv = hq[2] + (hit_d_axis < 0 ? 0.4f : 1.3f);
          }
          const float cosi = std::max(0.05f, std::abs(hit_d_axis) / dlen);
          const float fp = best_t * ray_scale_[k] / std::sqrt(cosi);
          const int face = hit_axis * 2 + (hit_d_axis < 0 ? 1 : 0);  // the face the ray enters
          value = f.tex->sample(tu, tv, fp) * f.shade[face];
          if (lamp_on) {
            const float ex = hq[0] - f.lamp[0], ey = hq[1] - f.lamp[1], ez = hq[2] - f.lamp[2];
            value *= lamp_b + lamp_a / (lamp_r2 + ex * ex + ey * ey + ez * ez);
          }
        } else if (std::isfinite(best_t)) {
          const float px = Cx + best_t * (Rw[0] * dx + Rw[1] * dy + Rw[2]);
          const float py = Cy + best_t * (Rw[3] * dx + Rw[4] * dy + Rw[5]);
          const float cosi = std::max(0.05f, -dwz / dlen);
          const float fp = best_t * ray_scale_[k] / std::sqrt(cosi);
          value = floor_tex.sample(px, py, fp) * floor_shade;
          if (lamp_on) {
            const float ex = px - Lx, ey = py - Ly;
            value *= lamp_b + lamp_a / (lamp_r2 + ex * ex + ey * ey + Lz2);
          }
        }
        sum += value;
      }
      row[u] += sum * inv_n;
    }
  }
}

}  // namespace alight::sim
