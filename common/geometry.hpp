#pragma once
// Frames and transforms (docs/ARCHITECTURE.md "Frames"): world W z-up, body B x forward / y left /
// z up, camera C optical (x right, y down, z forward). Quaternions are Hamilton [w, x, y, z]
// rotating body to world. Paper symbols: R_V1 = R_WB at the reference image, R_c = R_BC,
// t_c = t_B_C (eqs. 3 and 6).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>

namespace alight {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;

/// Quaternion from [w, x, y, z] (LCM order), normalised.
Quaterniond quat_from_wxyz(const double q[4]);
/// [w, x, y, z] of a quaternion, with w >= 0 (one representative of +-q).
void quat_to_wxyz(const Quaterniond& q, double out[4]);

/// R = Rz(yaw) Ry(pitch) Rx(roll): the Z-Y-X Euler convention of attitude commands.
Matrix3d rotation_from_rpy(double roll_rad, double pitch_rad, double yaw_rad);
/// Inverse of rotation_from_rpy, (roll, pitch, yaw) with pitch in [-pi/2, pi/2].
Vector3d rpy_from_rotation(const Matrix3d& R);
/// Heading of the body x axis in the world xy plane [rad].
double yaw_of(const Matrix3d& R_WB);
/// Wraps an angle to (-pi, pi].
double wrap_angle(double a_rad);
/// Wraps an axis' direction to (-pi/2, pi/2]: a line's, where a and a + pi are the same.
double wrap_axis_angle(double a_rad);
/// Where the ray from `origin` along d (any length) meets the level plane z = z_m, in front of
/// the origin; nullopt for a ray parallel to the plane or pointing away from it.
std::optional<Vector3d> ray_at_height(const Vector3d& origin, const Vector3d& d, double z_m);

/// True when R is orthonormal with det R = +1 within `tol`.
bool is_rotation(const Matrix3d& R, double tol = 1e-9);
/// Closest rotation to a 3x3 matrix (SVD projection), for re-orthonormalising estimates.
Matrix3d nearest_rotation(const Matrix3d& M);
/// Skew-symmetric matrix [v]x.
Matrix3d skew(const Vector3d& v);

/// X_AB from R_AB and the origin of B in A.
Isometry3d make_transform(const Matrix3d& R_AB, const Vector3d& p_A_B);

/// Standard camera mountings, R_BC (camera axes expressed in body).
/// Downward: optical axis along -z_B, image "up" towards the nose (x_C = -y_B, y_C = -x_B).
Matrix3d R_BC_downward();
/// Forward: optical axis along x_B, image right = vehicle right (x_C = -y_B, y_C = -z_B).
Matrix3d R_BC_forward();

/// Camera pose in world: X_WC = X_WB X_BC (paper eq. 6 without the point).
Isometry3d camera_in_world(const Isometry3d& X_WB, const Isometry3d& X_BC);

}  // namespace alight
