#include "common/geometry.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cassert>
#include <cmath>

namespace alight {

Quaterniond quat_from_wxyz(const double q[4]) {
  Quaterniond out(q[0], q[1], q[2], q[3]);
  const double n = out.norm();
  assert(n > 0.0);
  out.coeffs() /= n;
  return out;
}

void quat_to_wxyz(const Quaterniond& q_in, double out[4]) {
  Quaterniond q = q_in.normalized();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  out[0] = q.w();
  out[1] = q.x();
  out[2] = q.y();
  out[3] = q.z();
}

Matrix3d rotation_from_rpy(double roll_rad, double pitch_rad, double yaw_rad) {
  return (Eigen::AngleAxisd(yaw_rad, Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch_rad, Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll_rad, Vector3d::UnitX()))
      .toRotationMatrix();
}

Vector3d rpy_from_rotation(const Matrix3d& R) {
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  const double roll = std::atan2(R(2, 1), R(2, 2));
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  return Vector3d(roll, pitch, yaw);
}

double yaw_of(const Matrix3d& R_WB) { return std::atan2(R_WB(1, 0), R_WB(0, 0)); }

double wrap_angle(double a) {
  a = std::remainder(a, 2.0 * M_PI);
  return a <= -M_PI ? a + 2.0 * M_PI : a;
}

double wrap_axis_angle(double a) {
  a = std::remainder(a, M_PI);
  return a <= -M_PI / 2 ? a + M_PI : a;
}

std::optional<Vector3d> ray_at_height(const Vector3d& origin, const Vector3d& d, double z_m) {
  if (!(std::abs(d.z()) > 1e-9)) return std::nullopt;
  const double lambda = (z_m - origin.z()) / d.z();
  if (!(lambda > 0)) return std::nullopt;
  return origin + lambda * d;
}

bool is_rotation(const Matrix3d& R, double tol) {
  return (R.transpose() * R - Matrix3d::Identity()).cwiseAbs().maxCoeff() <= tol &&
         std::abs(R.determinant() - 1.0) <= tol;
}

Matrix3d nearest_rotation(const Matrix3d& M) {
  Eigen::JacobiSVD<Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Matrix3d D = Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

Matrix3d skew(const Vector3d& v) {
  Matrix3d S;
  S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return S;
}

Isometry3d make_transform(const Matrix3d& R_AB, const Vector3d& p_A_B) {
  Isometry3d X = Isometry3d::Identity();
  X.linear() = R_AB;
  X.translation() = p_A_B;
  return X;
}

Matrix3d R_BC_downward() {
  Matrix3d R;
  R.col(0) = -Vector3d::UnitY();  // x_C
  R.col(1) = -Vector3d::UnitX();  // y_C
  R.col(2) = -Vector3d::UnitZ();  // z_C
  return R;
}

Matrix3d R_BC_forward() {
  Matrix3d R;
  R.col(0) = -Vector3d::UnitY();
  R.col(1) = -Vector3d::UnitZ();
  R.col(2) = Vector3d::UnitX();
  return R;
}

Isometry3d camera_in_world(const Isometry3d& X_WB, const Isometry3d& X_BC) { return X_WB * X_BC; }

}  // namespace alight
