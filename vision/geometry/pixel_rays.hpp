#pragma once
// The undistorted ray through each whole pixel of a distorting camera, kept once computed.
// Undistorting is an iteration per pixel (CameraModel::undistort); the ingress mask's grid, the
// faces' search and the landing's photometric gate ask for the same pixels' rays on every frame.
// The table is filled on first use of each pixel (no frame pays for the whole image at once), one
// table per thread (a bench flies several pipelines on threads of their own), made again when the
// camera changes. Its rays are CameraModel::ray's, bit for bit.

#include <vector>

#include "common/camera_model.hpp"

namespace alight::vision {

class PixelRays {
 public:
  /// CameraModel::ray at the pixel (x, y) (kept inside the image, computed each time outside).
  Vector3d at(int x, int y);

 private:
  friend PixelRays& pixel_rays(const CameraModel& camera);
  bool made_for(const CameraModel& c) const;
  CameraModel camera_;
  std::vector<Vector2d> xn_;  // row-major; NaN: not yet computed
};

/// This thread's table for `camera`; it holds that camera's rays until this thread next asks for
/// another camera's (so read it within one stage, never keep it across stages).
PixelRays& pixel_rays(const CameraModel& camera);

}  // namespace alight::vision
