#pragma once
// Predefined search paths of the detection phase (paper 3.4.1 "Platform Detection": "the vehicle
// follows a predefined path"; 4.3: for ingress "the vehicle flies a trajectory along a wall
// surface"), flown by a carrot that moves along the polyline at a set speed and waits for the
// vehicle when it falls behind.

#include <vector>

#include "common/geometry.hpp"

namespace alight::autonomy {

/// Boustrophedon ("lawnmower") over the rectangle [min, max] at height z: lanes along x, spaced
/// lane_spacing_m in y, alternating direction; the first lane at min.y, the last at max.y.
std::vector<Vector3d> lawnmower(const Vector2d& min_W, const Vector2d& max_W, double lane_spacing_m,
                                double z_m);

class PathFollower {
 public:
  /// Starts at `from` (the vehicle), then the points in order.
  void start(const Vector3d& from, std::vector<Vector3d> points);
  /// Moves the carrot speed * dt along the path if the vehicle is within lead_m of it.
  void step(const Vector3d& p_vehicle, double dt_s, double speed_mps, double lead_m);
  const Vector3d& carrot() const { return carrot_; }
  /// Velocity of the carrot during the last step (feed-forward) [m/s].
  const Vector3d& carrot_velocity() const { return v_; }
  /// Carrot at the last point and the vehicle within tol_m of it.
  bool finished(const Vector3d& p_vehicle, double tol_m) const;
  bool empty() const { return points_.empty(); }

 private:
  std::vector<Vector3d> points_;
  size_t next_ = 0;
  Vector3d carrot_ = Vector3d::Zero();
  Vector3d v_ = Vector3d::Zero();
};

}  // namespace alight::autonomy
