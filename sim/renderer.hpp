#pragma once
// Camera image of a Scene by exact per-pixel ray casting (Appel 1968; ray-box slab test of Kay and
// Kajiya, SIGGRAPH 1986) for the paper's camera (section 4.1): each pixel's ray (undistorted
// through the camera model, so lens distortion is rendered exactly) is intersected analytically
// with the floor plane and the boxes; the nearest hit is textured with trilinear mip-mapping, the
// level chosen from the pixel's footprint on the surface (distance and incidence), and shaded by
// a Lambertian light times the lamp's falloff (Scene::illumination). Rays are precomputed once
// per camera model; per frame, boxes are culled against 16x16-pixel tiles by the bounds of their
// projection. Each row is rendered in passes over its rays that compile to SIMD code
// (renderer.cpp).

#include <opencv2/core.hpp>
#include <vector>

#include "common/camera_model.hpp"
#include "sim/scene.hpp"

namespace alight::sim {

class Renderer {
 public:
  /// `supersample` rays per pixel side (1: one ray through the pixel centre).
  explicit Renderer(const CameraModel& model, int supersample = 1);

  /// Noise-free mono8 image from camera pose X_WC (camera optical frame to world). `gain`
  /// scales the brightness (exposure).
  cv::Mat render(const Scene& scene, const Isometry3d& X_WC, float gain = 1.f) const;
  /// Adds `weight` x the radiance seen from X_WC to a CV_32F image (for motion blur).
  void accumulate(const Scene& scene, const Isometry3d& X_WC, float weight, cv::Mat& acc) const;
  /// The same for rows [row0, row1) only, on the calling thread (a rolling shutter's band of
  /// rows, each band from its own pose).
  void accumulate_rows(const Scene& scene, const Isometry3d& X_WC, float weight, int row0, int row1,
                       cv::Mat& acc) const;

  /// Use up to this many threads (cv::parallel_for_ stripes); 1 renders on the calling thread.
  void set_threads(int n) { threads_ = n < 1 ? 1 : n; }
  const CameraModel& model() const { return model_; }
  /// Grey level of the background (nothing hit: beyond the floor's horizon) [0, 255].
  static constexpr float kBackground = 40.f;

 private:
  void render_rows(const Scene& scene, const Isometry3d& X_WC, float weight, int row0, int row1,
                   float* out, size_t out_step) const;

  CameraModel model_;
  int ss_ = 1;
  int threads_ = 1;
  int tiles_x_ = 0, tiles_y_ = 0;
  // Per sub-ray: direction (x, y, 1) in camera coordinates and the footprint of a (sub-)pixel
  // at unit depth times the ray's length, and that length |(x, y, 1)|.
  std::vector<float> ray_x_, ray_y_, ray_scale_, ray_len_;
  // Per tile: bounds of its rays' (x, y) for culling.
  std::vector<cv::Vec4f> tile_bounds_;
};

}  // namespace alight::sim
