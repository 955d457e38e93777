#pragma once
// The known floor's per-match verdict under one rotation (known_floor.hpp, steps 1-2): the
// innermost loop of the landing's plane fit, run once per rotation hypothesis over every match.
// Vectorised four matches at a time with the scalar loop's arithmetic in the scalar loop's order
// (separate multiply and add, IEEE division and square root), so both give the same bits; the
// scalar loop is kept for machines without AVX2 and as the test's reference.

#include <cmath>
#include <vector>

#include "common/geometry.hpp"

namespace alight::vision {

/// The point x1 of a plane of inverse distance rho, carried into camera 2 (unnormalised):
/// H = R (I - t n^T rho) applied to x1 (eq. 2 with the metric t12).
inline Vector3d plane_carry(const Matrix3d& R, const Vector3d& t, const Vector3d& n, double rho,
                            const Vector3d& x1) {
  return R * (x1 - t * (rho * n.dot(x1)));
}

/// Pixel residual of p against the ray x2 (f: focal length [px]), and its Jacobian on p; false
/// behind camera 2 or where the residual is not finite.
inline bool plane_residual(const Vector3d& p, const Vector3d& x2, double f, Vector2d* r,
                           Eigen::Matrix<double, 2, 3>* J = nullptr) {
  if (!(p.z() > 1e-9)) return false;
  const double iz = 1.0 / p.z();
  *r = f * (p.head<2>() * iz - x2.head<2>());
  if (J) *J << f * iz, 0, -f * p.x() * iz * iz, 0, f * iz, -f * p.y() * iz * iz;
  return std::isfinite(r->x()) && std::isfinite(r->y());
}

struct PerMatch {
  double err_floor = 1e9;                         ///< transfer error under the floor [px]
  double rho = 0, half_width = 0, err_rho = 1e9;  ///< best inverse distance, its tolerance
};

/// Each match (x1[i] in camera 1, x2[i] in camera 2, normalised image coordinates with z = 1)
/// under rotation R, translation t and the floor of unit normal n at inverse distance rho_floor:
/// its floor error, its own best inverse distance (1-D least squares of the cross-multiplied
/// equations) and the interval of inverse distances that keeps it within thr pixels (f: focal
/// length [px]). Defaults where a match is behind camera 2 or has no parallax.
void classify_floor_matches(const std::vector<Vector3d>& x1, const std::vector<Vector3d>& x2,
                            const Matrix3d& R, const Vector3d& t, const Vector3d& n,
                            double rho_floor, double f, double thr, std::vector<PerMatch>* out);

/// The same without the AVX2 variant (exposed for the test that both agree bit for bit).
void classify_floor_matches_scalar(const std::vector<Vector3d>& x1, const std::vector<Vector3d>& x2,
                                   const Matrix3d& R, const Vector3d& t, const Vector3d& n,
                                   double rho_floor, double f, double thr,
                                   std::vector<PerMatch>* out);

}  // namespace alight::vision
