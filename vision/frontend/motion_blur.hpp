#pragma once
// How far the floor's image moves during one exposure (beyond the paper). A feature in a
// frame exposed while the camera turns or moves is the image smeared along that motion: its
// detector response and descriptor change, and its position is the smear's centre, which can
// differ from the mid-exposure projection by a pixel or more. At the search path's turns, frames
// exposed through a 1-2 rad/s pitch gave matches that no plane explains and a "top" from them.
//
// The motion field of a static point at normalised image point (x, y) and depth Z, for a camera
// moving with velocity v and angular rate w (both in the camera frame), is (Longuet-Higgins and
// Prazdny 1980):
//   du/dt = (x v_z - v_x) / Z + x y w_x - (1 + x^2) w_y + y w_z
//   dv/dt = (y v_z - v_y) / Z + (1 + y^2) w_x - x y w_y - x w_z
// in normalised units per second; times the focal length and the exposure it is the smear's
// length in pixels. Z is the depth of the floor plane along each ray (a ray that misses the
// floor, or meets it farther than max_depth_m, counts as infinitely far: rotation only).

#include "common/camera_model.hpp"
#include "common/camera_mount.hpp"
#include "common/pose_buffer.hpp"

namespace alight::vision {

/// The longest smear [px] of the floor z = floor_z_m [m, world] over a 5 x 5 grid of pixels
/// spanning the image, for a camera on the body of `pose` (its velocity and body angular rate are
/// used, taken as constant over the exposure) exposed for exposure_s [s]. 0 for exposure_s <= 0.
double floor_motion_blur_px(const CameraModel& camera, const CameraMount& mount,
                            const PoseSample& pose, double floor_z_m, double exposure_s,
                            double max_depth_m = 100.0);

}  // namespace alight::vision
