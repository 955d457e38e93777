#pragma once
// Where a camera sits on the vehicle (paper eq. 3 and 6: R_c = R_BC, t_c = t_B_C), read from the
// `cameras:` section of a vehicle file:
//
//   cameras:
//     downward:                      # used by the landing mission
//       camera_info: ../cameras/firefly_mv_4mm.yaml   # relative to the vehicle file
//       mount: downward              # downward | forward: the standard R_BC (common/geometry.hpp)
//       rpy_offset_deg: [0, 0, 0]    # small calibrated rotation applied after the mount [deg]
//       t_B_C_m: [0.0, 0.0, -0.06]   # camera centre in body [m]
//     forward: {...}                 # used by the ingress mission

#include <array>
#include <string>
#include <vector>

#include "common/camera_model.hpp"
#include "common/geometry.hpp"
#include "common/param_schema.hpp"

namespace alight {

/// One camera's section of `cameras:` as written (common/param_schema.hpp declares each key).
struct CameraMountParams {
  std::string camera_info;  ///< resolved against the vehicle file's folder when read
  std::string mount = "downward";
  std::array<double, 3> rpy_offset_deg{0, 0, 0};
  Vector3d t_B_C_m = Vector3d::Zero();

  static const ParamSchema<CameraMountParams>& schema();
  void validate() const;
};

struct CameraMount {
  std::string name;                   ///< key under `cameras:` (downward, forward)
  std::string camera_info_path;       ///< resolved path of the camera_info YAML
  Matrix3d R_BC = R_BC_downward();    ///< camera axes in body (R_c in eq. 6)
  Vector3d t_B_C = Vector3d::Zero();  ///< camera centre in body [m] (t_c in eqs. 3 and 6)

  Isometry3d X_BC() const { return make_transform(R_BC, t_B_C); }
};

/// The mounting that validated parameters describe.
CameraMount camera_mount(const std::string& name, const CameraMountParams& params);

/// Reads cameras.<name> from a vehicle file node (the file's top level).
CameraMountParams load_camera_mount_params(const ParamNode& vehicle_root, const std::string& name);
CameraMount load_camera_mount(const ParamNode& vehicle_root, const std::string& name);

/// The names under `cameras:` in file order (none without the section).
std::vector<std::string> camera_names(const ParamNode& vehicle_root);

}  // namespace alight
