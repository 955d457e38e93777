#pragma once
// Rolling-shutter geometry (beyond the paper, whose Firefly MV has a global shutter). A
// rolling-shutter sensor exposes row v line_delay x v after row 0; the frame's stamp and the pose
// the pipeline is given name row 0's time. A feature on row v was therefore seen from where the
// camera was v x line_delay later: over a 5-20 ms readout at 0.4 m/s and 0.3 rad/s that is 2-8 mm
// and 1.5-6 mrad, a few pixels at 1.5 m, which the homographies of paper 3.1.2 would otherwise
// absorb as a false plane (the bottom rows shifted against the top ones) or as parallax.
//
// Each feature's ray is brought to the frame's common epoch, row 0's camera, with the camera's
// motion over the readout taken as constant: the pose's velocity and body angular rate (motion
// capture's or the onboard estimate's), the model of Meingast, Geyer and Sastry ("Geometric models
// of rolling-shutter cameras", OMNIVIS 2005) that Hedborg, Forssen, Felsberg and Ringaby
// ("Rolling shutter bundle adjustment", CVPR 2012) correct per row. The camera at row v is
// X_C0_Cv = (Exp(w_C dt), v_C dt), dt = v x line_delay. The rotation needs no depth; the
// translation needs the point's depth, taken from a plane known beforehand (landing: the floor;
// ingress: the wall the previous frame measured); without one the correction is rotation only.
// With line_delay 0 (a global shutter) nothing is computed and every ray is the lens's own.

#include <cstdint>
#include <optional>
#include <vector>

#include "common/camera_model.hpp"
#include "common/camera_mount.hpp"
#include "common/pose_buffer.hpp"

namespace alight::vision {

/// A plane of the scene in world: n_W . p = d_W (n_W unit).
struct ScenePlane {
  Vector3d n_W = Vector3d::UnitZ();
  double d_W = 0.0;  ///< [m]
};

/// The camera's motion over one frame's readout, in row 0's camera axes.
struct Readout {
  double line_delay_s = 0.0;        ///< 0: a global shutter, nothing to correct [s]
  Vector3d w_C = Vector3d::Zero();  ///< angular rate in the camera's axes [rad/s]
  Vector3d v_C = Vector3d::Zero();  ///< the camera centre's velocity in row 0's axes [m/s]
  Vector3d n_C = Vector3d::Zero();  ///< the depth plane n_C . X = d_C in row 0's camera; zero:
  double d_C = 0.0;                 ///< no plane (rotation only) [m]
  bool rolling() const { return line_delay_s > 0.0; }
};

/// The readout of a frame taken from the body pose `pose` (at row 0's time) through `mount`;
/// `plane`: the scene plane depths are taken from (nullopt: rotation only). A line delay that is
/// not positive and finite gives a global shutter's readout (rolling() false).
Readout readout_motion(const PoseSample& pose, const CameraMount& mount, double line_delay_s,
                       const std::optional<ScenePlane>& plane);

/// The normalised ray (x, y, 1) in row 0's camera of the point recorded at raw pixel `pixel`
/// (its row's time). Equals camera.ray(pixel) when the readout is not rolling.
Vector3d ray_at_epoch(const CameraModel& camera, const Vector2d& pixel, const Readout& m);

/// The inverse: the raw pixel where the point on row 0's ray `r0` (any positive scale) was
/// recorded, by fixed-point iteration on its row; nullopt when it is behind the camera at its
/// row's time. Equals camera.project(r0) when the readout is not rolling.
std::optional<Vector2d> pixel_of_epoch_ray(const CameraModel& camera, const Vector3d& r0,
                                           const Readout& m);

/// pixel_of_epoch_ray of one frame, tabulated for the stages that map thousands of rays a frame
/// (the photometric gate, the rim search). The readout moves a ray's pixel by a few pixels,
/// smoothly across the image (the row's time, the lens and the plane's depth all vary slowly), so
/// that shift, taken exactly at the nodes of a kStepPx grid over the image and kMarginPx around it,
/// is interpolated bilinearly between them at a fraction of the exact mapping's three
/// projections. Nodes and cells are computed on first use and kept: one object serves one
/// frame's stages on one thread. Rays off the grid, in a cell with a node the exact mapping
/// refuses, or astride the plane's horizon (depth on one side, direction only on the other) take
/// the exact mapping.
class EpochPixelGrid {
 public:
  static constexpr int kStepPx = 8, kMarginPx = 16;
  /// `camera` must outlive the grid; `m` rolling.
  EpochPixelGrid(const CameraModel& camera, const Readout& m);
  /// pixel_of_epoch_ray(camera, r0, m) to interpolation's error (test: under 1e-3 px at 40 us a
  /// row and 0.6 rad/s); nullopt where it gives nullopt, or r0 is not in front of row 0's camera.
  std::optional<Vector2d> pixel(const Vector3d& r0) const;

 private:
  enum class Node : uint8_t { kUnset, kDepth, kDirection, kRefused };
  enum class Cell : uint8_t { kUnset, kInterpolated, kExact };
  Node node(int i, int j) const;
  Cell cell(int i, int j) const;
  std::optional<Vector2d> global_pixel(const Vector3d& r0) const;

  const CameraModel* camera_;
  Readout m_;
  bool pinhole_;
  int nx_, ny_;
  // Filled on first use: each node's shift and kind, each cell's way.
  mutable std::vector<Vector2d> shift_;
  mutable std::vector<Node> node_;
  mutable std::vector<Cell> cell_;
};

}  // namespace alight::vision
