#pragma once
// Pinhole camera with plumb_bob (Brown-Conrady k1 k2 p1 p2 k3) distortion, as in the ROS
// camera_info layout that calibration writes and sim / vision read, or with the equidistant
// fisheye model (Kannala and Brandt, PAMI 2006, as OpenCV's cv::fisheye and ROS's
// "equidistant": theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8), the
// image radius proportional to theta_d). Pixel (u, v): u right, v down, origin at the centre of
// the top-left pixel.

#include <array>
#include <optional>
#include <string>

#include "common/geometry.hpp"

namespace alight {

struct CameraModel {
  std::string name = "firefly_mv_4mm";
  int width = 640;                    ///< [px]
  int height = 480;                   ///< [px]
  double fx = 666.667, fy = 666.667;  ///< focal length [px]; 4 mm lens / 6 um pixels
  double cx = 319.5, cy = 239.5;      ///< principal point [px]
  /// plumb_bob k1, k2, p1, p2, k3 (all zero: no distortion); equidistant k1, k2, k3, k4, 0
  std::array<double, 5> D{};
  enum class Distortion { kPlumbBob, kEquidistant };
  Distortion distortion = Distortion::kPlumbBob;

  /// The paper's camera: Point Grey Firefly MV (6 um pixels, 640x480) with a 4 mm lens.
  static CameraModel firefly_mv_4mm();

  Matrix3d K() const;
  /// False only for a plumb_bob model with all coefficients zero (a fisheye always distorts).
  bool has_distortion() const;
  /// Applies the distortion to a normalised image point (x/z, y/z).
  Vector2d distort(const Vector2d& xn) const;
  /// Inverts distort() by fixed-point iteration (converges for realistic lenses).
  Vector2d undistort(const Vector2d& xd) const;
  /// Pixel of a point in camera coordinates; nullopt when it is not in front of the camera.
  std::optional<Vector2d> project(const Vector3d& p_C) const;
  /// Normalised, undistorted ray (x, y, 1) through a pixel (paper eq. 4's r).
  Vector3d ray(const Vector2d& pixel) const;
  bool in_image(const Vector2d& pixel, double margin_px = 0.0) const;

  void validate() const;  ///< throws ParamError naming the field and its value
};

/// Reads a ROS camera_info YAML file (image_width, image_height, camera_name, camera_matrix,
/// distortion_model, distortion_coefficients). Throws ParamError naming file, key and value.
CameraModel load_camera_info(const std::string& path);
/// Writes the ROS camera_info layout (with identity rectification and P = [K | 0]).
void save_camera_info(const std::string& path, const CameraModel& cam);
/// The YAML text save_camera_info writes.
std::string camera_info_yaml(const CameraModel& cam);

}  // namespace alight
