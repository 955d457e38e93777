#pragma once
// Shared input and output of the landing and ingress targets (paper 3.2 and 3.3): the matched
// features of the reference (1) and current (2) image with the poses of both, and what a target
// detector reports for one frame.

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "common/camera_model.hpp"
#include "common/camera_mount.hpp"
#include "common/pose_buffer.hpp"
#include "vision/status.hpp"

namespace alight::vision {

/// Matched features between the reference and the current image.
struct Correspondences {
  std::vector<Vector2d> x1, x2;  ///< undistorted pixels (K * ray) in the reference / current image
  std::vector<Vector2d> u1, u2;  ///< raw (distorted) pixels in the reference / current image
  PoseSample pose_1, pose_2;     ///< motion-capture poses at the two exposures
  const CameraModel* camera = nullptr;
  const CameraMount* mount = nullptr;
  size_t size() const { return x1.size(); }
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
