#pragma once
// Shared input and output of the landing and ingress targets (paper 3.2 and 3.3): the matched
// features of the reference (1) and current (2) image with the poses of both, and what a target
// detector reports for one frame.

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "common/camera_model.hpp"
#include "common/camera_mount.hpp"
#include "common/pose_buffer.hpp"
#include "vision/geometry/rolling_shutter.hpp"
#include "vision/status.hpp"

namespace alight::vision {

/// Matched features between the reference and the current image.
struct Correspondences {
  std::vector<Vector2d> x1, x2;  ///< undistorted pixels (K * ray) in the reference / current image
  std::vector<Vector2d> u1, u2;  ///< raw (distorted) pixels in the reference / current image
  /// The rays (x, y, 1) of x1 / x2 (K^-1 x): the lens undone and, under a rolling shutter, at
  /// each frame's row 0 (rolling_shutter.hpp). Empty: camera->ray(u1 / u2).
  std::vector<Vector3d> r1, r2;
  /// Each frame's readout (null or not rolling: a global shutter), for the stages that sample
  /// the raw images at points of the geometry.
  const Readout* readout_1 = nullptr;
  const Readout* readout_2 = nullptr;
  /// The readouts' inverses tabulated (rolling_shutter.hpp), set with each rolling readout: the
  /// photometric gate reads the reference's through grid_1 alone. Null: pixel1 / pixel2 map
  /// each ray exactly.
  std::shared_ptr<const EpochPixelGrid> grid_1, grid_2;
  PoseSample pose_1, pose_2;  ///< motion-capture poses at the two exposures
  const CameraModel* camera = nullptr;
  const CameraMount* mount = nullptr;
  size_t size() const { return x1.size(); }
  Vector3d ray1(size_t k) const { return r1.empty() ? camera->ray(u1[k]) : r1[k]; }
  Vector3d ray2(size_t k) const { return r2.empty() ? camera->ray(u2[k]) : r2[k]; }
  /// The ray of the reference's / current frame's row 0 through its raw pixel u.
  Vector3d ray_of_pixel1(const Vector2d& u) const {
    return readout_1 ? ray_at_epoch(*camera, u, *readout_1) : camera->ray(u);
  }
  Vector3d ray_of_pixel2(const Vector2d& u) const {
    return readout_2 ? ray_at_epoch(*camera, u, *readout_2) : camera->ray(u);
  }
  /// The raw pixel of a ray (any positive scale) of the reference's / current frame's row 0.
  std::optional<Vector2d> pixel1(const Vector3d& r) const { return pixel(r, readout_1, grid_1); }
  std::optional<Vector2d> pixel2(const Vector3d& r) const { return pixel(r, readout_2, grid_2); }

 private:
  std::optional<Vector2d> pixel(const Vector3d& r, const Readout* m,
                                const std::shared_ptr<const EpochPixelGrid>& grid) const {
    if (grid) return grid->pixel(r);
    return m && m->rolling() ? pixel_of_epoch_ray(*camera, r, *m) : camera->project(r);
  }
};

/// Role of each correspondence, for the diagnostic image.
enum class Label : uint8_t { kOutlier = 0, kDominant = 1, kTarget = 2 };

/// What a target detector found in one frame.
struct TargetEstimate {
  Vector3d p_W = Vector3d::Zero();    ///< waypoint: platform / opening centre in world [m]
  Vector3d n_W = Vector3d::UnitZ();   ///< unit normal of the target plane, towards the camera
  Vector2d pixel = Vector2d::Zero();  ///< aiming point in the current (raw) image [px]
  double height_m = 0.0;              ///< landing: platform top above the floor [m]
  double size_m[2] = {0, 0};  ///< landing: size (long, short), side_from_extent of the features'
                              ///< extent; ingress: width, height [m]
  double yaw_rad = 0.0;  ///< landing: long axis direction about world z, in (-pi/2, pi/2] [rad]
  int n_inliers_dominant = 0;     ///< floor / wall inliers
  int n_inliers_target = 0;       ///< platform inliers / off-wall features in the opening
  std::vector<Vector2d> outline;  ///< platform hull / opening box in the current image [px]
};

/// The detector's answer with everything the diagnostics want also when nothing was found.
struct TargetOutcome {
  Reason reason = Reason::kOk;
  TargetEstimate estimate;       ///< valid when reason == kOk (counts always)
  std::vector<Label> labels;     ///< one per correspondence
  std::vector<cv::Vec4i> lines;  ///< ingress: the kept Hough segments (raw pixels)
};

}  // namespace alight::vision
