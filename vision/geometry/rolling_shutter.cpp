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

EpochPixelGrid::EpochPixelGrid(const CameraModel& camera, const Readout& m)
    : camera_(&camera),
      m_(m),
      pinhole_(!camera.has_distortion()),
      nx_((camera.width - 1 + 2 * kMarginPx) / kStepPx + 2),
      ny_((camera.height - 1 + 2 * kMarginPx) / kStepPx + 2) {}

// Node (i, j) sits at raw pixel (i, j) x kStepPx - kMarginPx, a global shutter's pixel of its ray.
EpochPixelGrid::Node EpochPixelGrid::node(int i, int j) const {
  const size_t at = static_cast<size_t>(j) * nx_ + i;
  if (node_[at] != Node::kUnset) return node_[at];
  node_[at] = Node::kRefused;
  const Vector2d g(i * kStepPx - kMarginPx, j * kStepPx - kMarginPx);
  const Vector3d r = camera_->ray(g);
  // A lens model's inverse can fail far out (a fisheye past its valid angle): such a node would
  // interpolate a ray that is not its pixel's.
  const auto back = camera_->project(r);
  if (!back || (*back - g).norm() > 1e-6) return node_[at];
  const auto u = pixel_of_epoch_ray(*camera_, r, m_);
  if (!u) return node_[at];
  shift_[at] = *u - g;
  node_[at] = plane_depth(m_, r, Vector3d::Zero()) ? Node::kDepth : Node::kDirection;
  return node_[at];
}

// Cell (i, j) spans nodes (i, j) to (i + 1, j + 1): interpolated where its four corners are
// mapped with one model.
EpochPixelGrid::Cell EpochPixelGrid::cell(int i, int j) const {
  if (shift_.empty()) {
    shift_.resize(static_cast<size_t>(nx_) * ny_);
    node_.resize(shift_.size(), Node::kUnset);
    cell_.resize(static_cast<size_t>(nx_ - 1) * (ny_ - 1), Cell::kUnset);
  }
  Cell& c = cell_[static_cast<size_t>(j) * (nx_ - 1) + i];
  if (c != Cell::kUnset) return c;
  const Node a = node(i, j);
  const bool one_model =
      a != Node::kRefused && node(i + 1, j) == a && node(i, j + 1) == a && node(i + 1, j + 1) == a;
  c = one_model ? Cell::kInterpolated : Cell::kExact;
  return c;
}

// CameraModel::project, in place for a lens without distortion (the lookup's hot path).
std::optional<Vector2d> EpochPixelGrid::global_pixel(const Vector3d& r0) const {
  if (!pinhole_) return camera_->project(r0);
  if (r0.z() <= 1e-9) return std::nullopt;
  return Vector2d(camera_->fx * (r0.x() / r0.z()) + camera_->cx,
                  camera_->fy * (r0.y() / r0.z()) + camera_->cy);
}

std::optional<Vector2d> EpochPixelGrid::pixel(const Vector3d& r0) const {
  const auto g = global_pixel(r0);
  if (!g) return g;
  const double x = (g->x() + kMarginPx) / kStepPx, y = (g->y() + kMarginPx) / kStepPx;
  if (!(x >= 0 && y >= 0 && x < nx_ - 1 && y < ny_ - 1))
    return pixel_of_epoch_ray(*camera_, r0, m_);
  const int i = static_cast<int>(x), j = static_cast<int>(y);
  if (cell(i, j) != Cell::kInterpolated) return pixel_of_epoch_ray(*camera_, r0, m_);
  const Vector2d* top = &shift_[static_cast<size_t>(j) * nx_ + i];
  const Vector2d* bottom = top + nx_;
  const double fx = x - i, fy = y - j;
  return *g + (1 - fy) * ((1 - fx) * top[0] + fx * top[1]) +
         fy * ((1 - fx) * bottom[0] + fx * bottom[1]);
}

}  // namespace alight::vision
