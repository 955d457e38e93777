#include "vision/frontend/motion_blur.hpp"

#include <algorithm>
#include <cmath>

namespace alight::vision {

double floor_motion_blur_px(const CameraModel& camera, const CameraMount& mount,
                            const PoseSample& pose, double floor_z_m, double exposure_s,
                            double max_depth_m) {
  if (!(exposure_s > 0)) return 0.0;
  const Matrix3d R_WB = pose.q_WB.normalized().toRotationMatrix();
  const Matrix3d R_WC = R_WB * mount.R_BC;
  const Vector3d p_W_C = pose.p_W_B + R_WB * mount.t_B_C;
  // The camera centre's velocity: the body's plus the lever arm's turn.
  const Vector3d v_W_C = pose.v_W_B + R_WB * pose.omega_B.cross(mount.t_B_C);
  const Vector3d v_C = R_WC.transpose() * v_W_C;
  const Vector3d w_C = mount.R_BC.transpose() * pose.omega_B;
  double longest_px = 0.0;
  constexpr int kGrid = 5;
  for (int i = 0; i < kGrid; ++i)
    for (int j = 0; j < kGrid; ++j) {
      const Vector2d px((camera.width - 1) * i / double(kGrid - 1),
                        (camera.height - 1) * j / double(kGrid - 1));
      const Vector3d r_C = camera.ray(px);  // (x, y, 1)
      const double x = r_C.x(), y = r_C.y();
      const double d_z = (R_WC * r_C).z();  // the ray's world z per unit depth
      const double depth_m = std::abs(d_z) > 1e-9 ? (floor_z_m - p_W_C.z()) / d_z : -1.0;
      const double inv_depth = depth_m > 0 && depth_m <= max_depth_m ? 1.0 / depth_m : 0.0;
      const double du = (x * v_C.z() - v_C.x()) * inv_depth + x * y * w_C.x() -
                        (1 + x * x) * w_C.y() + y * w_C.z();
      const double dv = (y * v_C.z() - v_C.y()) * inv_depth + (1 + y * y) * w_C.x() -
                        x * y * w_C.y() - x * w_C.z();
      longest_px = std::max(longest_px, std::hypot(camera.fx * du, camera.fy * dv));
    }
  return longest_px * exposure_s;
}

}  // namespace alight::vision
