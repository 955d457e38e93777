#include "vision/geometry/pixel_rays.hpp"

#include <cmath>
#include <limits>

namespace alight::vision {

bool PixelRays::made_for(const CameraModel& c) const {
  return !xn_.empty() && c.width == camera_.width && c.height == camera_.height &&
         c.fx == camera_.fx && c.fy == camera_.fy && c.cx == camera_.cx && c.cy == camera_.cy &&
         c.D == camera_.D && c.distortion == camera_.distortion;
}

Vector3d PixelRays::at(int x, int y) {
  if (x < 0 || y < 0 || x >= camera_.width || y >= camera_.height)
    return camera_.ray(Vector2d(x, y));
  Vector2d& xn = xn_[static_cast<size_t>(y) * camera_.width + x];
  if (std::isnan(xn.x())) xn = camera_.ray(Vector2d(x, y)).head<2>();
  return Vector3d(xn.x(), xn.y(), 1.0);
}

PixelRays& pixel_rays(const CameraModel& camera) {
  thread_local PixelRays table;
  if (!table.made_for(camera)) {
    table.camera_ = camera;
    table.xn_.assign(static_cast<size_t>(camera.width) * camera.height,
                     Vector2d::Constant(std::numeric_limits<double>::quiet_NaN()));
  }
  return table;
}

}  // namespace alight::vision
