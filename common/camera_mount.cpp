#include "common/camera_mount.hpp"

#include <cmath>

namespace alight {

const ParamSchema<CameraMountParams>& CameraMountParams::schema() {
  using P = CameraMountParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("camera_info", &P::camera_info, Range::any(), "",
          "intrinsics in the ROS camera_info layout (alight-calibrate writes one)")
        .required()
        .path()
        .check([](const P& p) { return !p.camera_info.empty(); }, "must name a camera_info file");
    s.add("mount", &P::mount, Range::any(), "",
          "the standard camera axes in body, R_BC (common/geometry.hpp)")
        .required()
        .one_of({"downward", "forward"});
    s.add("rpy_offset_deg", &P::rpy_offset_deg, Range::closed(-45, 45), "deg",
          "small calibrated rotation (roll, pitch, yaw) applied after the mount");
    s.add("t_B_C_m", &P::t_B_C_m, Range::any(), "m", "camera centre in body (t_c, eqs. 3 and 6)")
        .required()
        .check([](const P& p) { return p.t_B_C_m.norm() < 1.0; },
               "camera more than 1 m from the body origin");
    return s;
  }();
  return schema;
}

void CameraMountParams::validate() const { schema().validate(*this); }

CameraMount camera_mount(const std::string& name, const CameraMountParams& p) {
  CameraMount m;
  m.name = name;
  m.camera_info_path = p.camera_info;
  const auto& rpy = p.rpy_offset_deg;
  m.R_BC = (p.mount == "forward" ? R_BC_forward() : R_BC_downward()) *
           rotation_from_rpy(rpy[0] * M_PI / 180, rpy[1] * M_PI / 180, rpy[2] * M_PI / 180);
  m.t_B_C = p.t_B_C_m;
  return m;
}

CameraMountParams load_camera_mount_params(const ParamNode& vehicle_root, const std::string& name) {
  CameraMountParams p;
  CameraMountParams::schema().read(vehicle_root.child("cameras").child(name), p);
  return p;
}

CameraMount load_camera_mount(const ParamNode& vehicle_root, const std::string& name) {
  return camera_mount(name, load_camera_mount_params(vehicle_root, name));
}

std::vector<std::string> camera_names(const ParamNode& vehicle_root) {
  std::vector<std::string> names;
  if (!vehicle_root.has("cameras")) return names;
  const YAML::Node cameras = vehicle_root.yaml()["cameras"];
  if (!cameras.IsMap()) return names;
  for (const auto& kv : cameras)
    if (kv.first.IsScalar()) names.push_back(kv.first.Scalar());
  return names;
}

}  // namespace alight
