// Rolling-shutter geometry (see rolling_shutter.hpp).
#include "vision/geometry/rolling_shutter.hpp"

#include <cmath>

namespace alight::vision {

namespace {

// Exp(phi) x: a readout turns the camera by a few mrad (0.5 rad/s over 20 ms is 0.01 rad),
// where the series to second order is off by angle^3 / 6 < 2e-7 rad, a ten-thousandth of a pixel,
// at a fraction of Rodrigues' cost (it runs per pixel in the photometric gate and the rim
// search); larger turns take the exact form.
Vector3d rotate(const Vector3d& phi, const Vector3d& x) {
  const double angle2 = phi.squaredNorm();
  if (angle2 > 0.05 * 0.05) {
    const double angle = std::sqrt(angle2);
    return Eigen::AngleAxisd(angle, phi / angle) * x;
  }
  const Vector3d px = phi.cross(x);
  return x + px + 0.5 * phi.cross(px);
}

// Depth along direction d (row 0's axes) of the plane point seen from a camera displaced by t;
// nullopt without a plane or where the ray misses it.
std::optional<double> plane_depth(const Readout& m, const Vector3d& d, const Vector3d& t) {
  if (m.n_C.squaredNorm() == 0.0) return std::nullopt;
  const double den = m.n_C.dot(d);
  if (std::abs(den) < 1e-9) return std::nullopt;
  const double depth = (m.d_C - m.n_C.dot(t)) / den;
  if (!(depth > 0.0) || !std::isfinite(depth)) return std::nullopt;
  return depth;
}

}  // namespace

Readout readout_motion(const PoseSample& pose, const CameraMount& mount, double line_delay_s,
                       const std::optional<ScenePlane>& plane) {
  Readout m;
  if (!(line_delay_s > 0.0) || !std::isfinite(line_delay_s)) return m;
  const Matrix3d R_WB = pose.q_WB.normalized().toRotationMatrix();
  const Matrix3d R_WC = R_WB * mount.R_BC;
  const Vector3d p_W_C = pose.p_W_B + R_WB * mount.t_B_C;
  // The camera centre's velocity: the body's plus the lever arm's turn.
  const Vector3d v_W_C = pose.v_W_B + R_WB * pose.omega_B.cross(mount.t_B_C);
  m.line_delay_s = line_delay_s;
  m.v_C = R_WC.transpose() * v_W_C;
  m.w_C = mount.R_BC.transpose() * pose.omega_B;
  if (plane) {
    m.n_C = R_WC.transpose() * plane->n_W;
    m.d_C = plane->d_W - plane->n_W.dot(p_W_C);
  }
  return m;
}

Vector3d ray_at_epoch(const CameraModel& camera, const Vector2d& pixel, const Readout& m) {
  const Vector3d r = camera.ray(pixel);
  if (!m.rolling()) return r;
  const double dt = pixel.y() * m.line_delay_s;
  const Vector3d d = rotate(m.w_C * dt, r);
  const Vector3d t = m.v_C * dt;
  Vector3d X = d;
  if (const auto depth = plane_depth(m, d, t)) X = *depth * d + t;
  if (!(X.z() > 1e-9)) X = d;
  if (!(X.z() > 1e-9)) return r;
  return X / X.z();
}

std::optional<Vector2d> pixel_of_epoch_ray(const CameraModel& camera, const Vector3d& r0,
                                           const Readout& m) {
  auto u = camera.project(r0);
  if (!m.rolling() || !u) return u;
  // The point itself where the plane gives its depth, else only its direction.
  std::optional<double> depth = plane_depth(m, r0, Vector3d::Zero());
  const Vector3d X0 = depth ? Vector3d(*depth * r0) : r0;
  // The first step moves the row by the readout's shift there (a few pixels), which changes
  // its time by a few line delays: the second moves it by about a hundredth of a pixel.
  for (int i = 0; i < 2; ++i) {
    const double dt = u->y() * m.line_delay_s;
    // R^T x = Exp(-phi) x.
    const Vector3d X_t = rotate(-m.w_C * dt, depth ? Vector3d(X0 - m.v_C * dt) : X0);
    u = camera.project(X_t);
    if (!u) return u;
  }
  return u;
}

}  // namespace alight::vision
