// Paper 3.1.2: Longuet-Higgins (1986) decomposition; see decomposition.hpp.
#include "vision/geometry/decomposition.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace alight::vision {

Matrix3d PlaneMotion::homography() const {
  return R_21 * (Matrix3d::Identity() - t_12 * n_1.transpose());
}

Matrix3d calibrate_homography(const Matrix3d& H_px, const Matrix3d& K) {
  return K.inverse() * H_px * K;
}

double rotation_angle(const Matrix3d& R_a, const Matrix3d& R_b) {
  // 2 asin(|R_a - R_b|_F / sqrt 8) stays accurate near zero, where acos of the trace does not.
  const double f = (R_a - R_b).norm() / std::sqrt(8.0);
  return 2.0 * std::asin(std::min(1.0, f));
}

double direction_angle(const Vector3d& a, const Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

std::vector<PlaneMotion> decompose_homography(const Matrix3d& H_cal,
                                              const std::vector<Vector3d>& rays_1,
                                              const DecompositionParams& params) {
  std::vector<PlaneMotion> out;
  if (!H_cal.allFinite()) return out;
  const Eigen::JacobiSVD<Matrix3d> svd(H_cal, Eigen::ComputeFullV);
  const Vector3d sv = svd.singularValues();
  if (!(sv(1) > 1e-12)) return out;
  Matrix3d H = H_cal / sv(1);  // Longuet-Higgins: the middle singular value of R(I - t n^T) is 1
  int votes = 0;
  for (const auto& x1 : rays_1) votes += (H * x1).z() > 0.0 ? 1 : -1;
  if (votes < 0) H = -H;  // x2 ~ H x1 with positive depth ratio

  const double s1 = sv(0) / sv(1), s3 = sv(2) / sv(1);
  if (s1 - s3 < params.min_singular_gap) return out;
  Matrix3d V = svd.matrixV();
  if (V.determinant() < 0) V = -V;
  const Vector3d v1 = V.col(0), v2 = V.col(1), v3 = V.col(2);
  const double a = std::sqrt(std::max(0.0, 1.0 - s3 * s3));
  const double b = std::sqrt(std::max(0.0, s1 * s1 - 1.0));
  const double c = std::sqrt(s1 * s1 - s3 * s3);
  const Vector3d us[2] = {(a * v1 + b * v3) / c, (a * v1 - b * v3) / c};
  for (const Vector3d& u : us) {
    Matrix3d U, W;
    U << v2, u, v2.cross(u);
    const Vector3d Hv2 = H * v2, Hu = H * u;
    W << Hv2, Hu, Hv2.cross(Hu);
    const Matrix3d R = nearest_rotation(W * U.transpose());
    const Vector3d N = v2.cross(u);
    const Vector3d T = (H - R) * N;  // H = R + T N^T (Ma et al.) with T = translation / distance
    const double t_norm = T.norm();
    if (!(t_norm > 1e-12)) continue;
    for (const double sign : {1.0, -1.0}) {
      PlaneMotion m;
      m.R_21 = R;
      m.t_12 = -sign * R.transpose() * T / t_norm;  // x2 = R (x1 - t12)
      m.n_1 = sign * N * t_norm;
      out.push_back(m);
    }
  }
  return out;
}

std::vector<PlaneMotion> positive_depth(const std::vector<PlaneMotion>& candidates,
                                        const std::vector<Vector3d>& rays_1,
                                        const std::vector<Vector3d>& rays_2,
                                        const DecompositionParams& params) {
  assert(rays_1.size() == rays_2.size());
  std::vector<PlaneMotion> out;
  const double need = params.min_front_fraction * double(rays_1.size());
  for (const auto& m : candidates) {
    const Vector3d n2 = m.n_2();
    if (1.0 - m.t_12.dot(m.n_1) <= 0.0) continue;  // cameras on opposite sides of the plane
    int front = 0;
    for (size_t i = 0; i < rays_1.size(); ++i)
      front += (m.n_1.dot(rays_1[i]) > 0.0 && n2.dot(rays_2[i]) > 0.0) ? 1 : 0;
    if (front >= need && front > 0) out.push_back(m);
  }
  return out;
}

Result<PlaneMotion> decompose(const Matrix3d& H_cal, const std::vector<Vector3d>& rays_1,
                              const std::vector<Vector3d>& rays_2, const DecompositionPrior& prior,
                              const DecompositionParams& params) {
  const auto all = decompose_homography(H_cal, rays_1, params);
  if (all.empty()) return Result<PlaneMotion>::fail(Reason::kSmallBaseline);
  const auto front = positive_depth(all, rays_1, rays_2, params);
  if (front.empty()) return Result<PlaneMotion>::fail(Reason::kDecompositionFailed);
  if (front.size() == 1) return Result<PlaneMotion>::ok(front[0]);
  auto best_by = [&](auto cost) {
    return *std::min_element(front.begin(), front.end(),
                             [&](const auto& p, const auto& q) { return cost(p) < cost(q); });
  };
  if (prior.R_21)
    return Result<PlaneMotion>::ok(
        best_by([&](const PlaneMotion& m) { return rotation_angle(m.R_21, *prior.R_21); }));
  if (prior.n_1)
    return Result<PlaneMotion>::ok(best_by(
        [&](const PlaneMotion& m) { return direction_angle(m.unit_normal_1(), *prior.n_1); }));
  // Without a prior two survivors are only acceptable when they coincide (translation along
  // the normal makes the two solutions one).
  bool same = true;
  for (const auto& m : front)
    same = same && rotation_angle(m.R_21, front[0].R_21) < 1e-6 &&
           direction_angle(m.n_1, front[0].n_1) < 1e-6;
  if (same) return Result<PlaneMotion>::ok(front[0]);
  return Result<PlaneMotion>::fail(Reason::kDecompositionAmbiguous);
}

}  // namespace alight::vision
