#include "autonomy/search_path.hpp"

#include <cassert>
#include <cmath>

namespace alight::autonomy {

std::vector<Vector3d> lawnmower(const Vector2d& min_W, const Vector2d& max_W, double lane_spacing_m,
                                double z_m) {
  assert(lane_spacing_m > 0);
  std::vector<Vector3d> pts;
  const double span = max_W.y() - min_W.y();
  const int lanes = 1 + static_cast<int>(std::ceil(span / lane_spacing_m - 1e-9));
  for (int i = 0; i < lanes; ++i) {
    const double y = lanes > 1 ? min_W.y() + span * i / (lanes - 1) : min_W.y();
    const bool forward = i % 2 == 0;
    pts.emplace_back(forward ? min_W.x() : max_W.x(), y, z_m);
    pts.emplace_back(forward ? max_W.x() : min_W.x(), y, z_m);
  }
  return pts;
}

void PathFollower::start(const Vector3d& from, std::vector<Vector3d> points) {
  points_ = std::move(points);
  points_.insert(points_.begin(), from);
  next_ = 1;
  carrot_ = from;
  v_.setZero();
}

void PathFollower::step(const Vector3d& p_vehicle, double dt_s, double speed_mps, double lead_m) {
  v_.setZero();
  if ((p_vehicle - carrot_).norm() > lead_m || dt_s <= 0) return;
  double remaining = speed_mps * dt_s;
  const Vector3d before = carrot_;
  while (remaining > 0 && next_ < points_.size()) {
    const Vector3d d = points_[next_] - carrot_;
    const double len = d.norm();
    if (len <= remaining) {
      carrot_ = points_[next_++];
      remaining -= len;
    } else {
      carrot_ += d / len * remaining;
      remaining = 0;
    }
  }
  v_ = (carrot_ - before) / dt_s;
}

bool PathFollower::finished(const Vector3d& p_vehicle, double tol_m) const {
  return next_ >= points_.size() && (p_vehicle - carrot_).norm() <= tol_m;
}

}  // namespace alight::autonomy
