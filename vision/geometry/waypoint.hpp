#pragma once
// Waypoint generation (paper 3.1.3, eqs. 3-6): scale from the motion-capture translation of the
// camera centre (eq. 3, including the camera-body offset t_c = t_B_C), ray-plane intersection
// in the current view (eqs. 4-5), transform to the world frame (eq. 6).
//
// Eq. 6 of the paper writes P_V1, R_V1; the point X_c of eq. 5 is in the current camera
// (it comes from the current ray and n2~), so it is mapped with the current pose P_V2, R_V2.

#include "common/camera_mount.hpp"
#include "common/pose_buffer.hpp"
#include "vision/geometry/decomposition.hpp"
#include "vision/params.hpp"
#include "vision/status.hpp"

namespace alight::vision {

/// Camera motion between the reference (1) and current (2) image from motion capture.
struct MocapMotion {
  Matrix3d R_21 = Matrix3d::Identity();  ///< camera 1 -> camera 2 axes
  Vector3d t_12 = Vector3d::Zero();      ///< camera 2 centre in camera 1 [m]
  double baseline_m = 0.0;               ///< s of eq. 3 = |c - c'| [m]
};

/// Eq. 3: c = P_V + R_V t_c; R21 = R_C2W R_WC1.
MocapMotion mocap_motion(const PoseSample& pose_1, const PoseSample& pose_2,
                         const CameraMount& mount);

struct Waypoint {
  Vector3d p_W = Vector3d::Zero();     ///< X_V of eq. 6: the point on the plane in world [m]
  Vector3d p_C2 = Vector3d::Zero();    ///< X_c of eq. 5: the point in the current camera [m]
  Vector3d n_W = Vector3d::UnitZ();    ///< unit plane normal in world, pointing towards the camera
  double distance_m = 0.0;             ///< current camera centre to the plane [m]
  double scale_m = 0.0;                ///< s of eq. 3 [m per baseline unit]
  double translation_angle_rad = 0.0;  ///< vision vs motion-capture t12 direction
  double rotation_error_rad = 0.0;     ///< vision vs motion-capture R21
};

/// Waypoint of the plane point seen along `ray_2` (normalised, undistorted (x2, y2, 1) in the
/// current image) given the decomposition of that plane's homography. Fails with
/// kSmallBaseline (s < min_baseline_m), kMotionDisagrees (the decomposed motion off motion
/// capture's beyond max_translation_angle_deg or max_rotation_error_deg) or kAimBehindCamera
/// (the ray does not meet the plane in front of the camera).
Result<Waypoint> compute_waypoint(const PlaneMotion& motion, const Vector3d& ray_2,
                                  const PoseSample& pose_1, const PoseSample& pose_2,
                                  const CameraMount& mount, const WaypointParams& params = {});

/// The image-plane angle (from the u axis towards v) of a fixed world direction d_W seen by a
/// camera with orientation R_WC: rotating the SURF sampling pattern by it makes descriptors of
/// all frames share one orientation (surf_descriptor.hpp).
double pattern_angle(const Matrix3d& R_WC, const Vector3d& d_W);

}  // namespace alight::vision
