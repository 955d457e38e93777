#include "common/camera_mount.hpp"

#include <cmath>
#include <filesystem>

namespace alight {

std::string resolve_relative(const std::string& relative_to_file, const std::string& path) {
  const std::filesystem::path p(path);
  if (p.is_absolute()) return path;
  return (std::filesystem::path(relative_to_file).parent_path() / p).lexically_normal().string();
}

CameraMount load_camera_mount(const ParamNode& vehicle_root, const std::string& name) {
  const ParamNode cam = vehicle_root.child("cameras").child(name);
  CameraMount m;
  m.name = name;
  std::string info;
  cam.require("camera_info", info);
  m.camera_info_path = resolve_relative(vehicle_root.file(), info);
  std::string mount = "downward";
  cam.require("mount", mount);
  if (mount == "downward") {
    m.R_BC = R_BC_downward();
  } else if (mount == "forward") {
    m.R_BC = R_BC_forward();
  } else {
    throw cam.error("mount", mount, "must be downward or forward");
  }
  std::array<double, 3> rpy{0, 0, 0};
  cam.read("rpy_offset_deg", rpy);
  for (double a : rpy)
    cam.check(std::abs(a) <= 45.0, "rpy_offset_deg", "offsets must be within 45 deg");
  m.R_BC =
      m.R_BC * rotation_from_rpy(rpy[0] * M_PI / 180, rpy[1] * M_PI / 180, rpy[2] * M_PI / 180);
  cam.require("t_B_C_m", m.t_B_C);
  cam.check(m.t_B_C.norm() < 1.0, "t_B_C_m", "camera more than 1 m from the body origin");
  cam.finish();
  return m;
}

}  // namespace alight
