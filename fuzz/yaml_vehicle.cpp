// A vehicle file (config/vehicles/*.yaml) through every component's loader, as each node reads
// it: autonomy, outer loop, vision (parameters and both camera mounts, with the camera_info a
// mount names) and the simulator (vehicle model and camera rig).
#include <optional>

#include "autonomy/params.hpp"
#include "common/camera_model.hpp"
#include "common/camera_mount.hpp"
#include "fuzz/fuzz_support.hpp"
#include "outer_loop/params.hpp"
#include "sim/params.hpp"
#include "vision/params.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  static fuzz::InputFile file("vehicles");
  const std::string& path = file.write(data, size);
  fuzz::expect_param_errors_only("autonomy::load_params", [&] { autonomy::load_params(path); });
  fuzz::expect_param_errors_only("outer_loop::load_params", [&] { outer_loop::load_params(path); });
  // As alight-vision reads it: the file once, then its parameters and its camera's mount from
  // that tree (both mounts here: the node takes the one its mission needs).
  std::optional<ParamNode> root;
  fuzz::expect_param_errors_only("ParamNode::load_file",
                                 [&] { root = ParamNode::load_file(path); });
  if (root) {
    fuzz::expect_param_errors_only("vision::load_node_params",
                                   [&] { vision::load_node_params(*root); });
    for (const char* mount_name : {"downward", "forward"})
      fuzz::expect_param_errors_only("load_camera_mount + load_camera_info", [&] {
        const CameraMount mount = load_camera_mount(*root, mount_name);
        load_camera_info(mount.camera_info_path);
      });
  }
  for (const char* mount_name : {"downward", "forward"})
    fuzz::expect_param_errors_only("sim::load_camera_rig",
                                   [&] { sim::load_camera_rig(path, mount_name); });
  fuzz::expect_param_errors_only("sim::load_vehicle_params",
                                 [&] { sim::load_vehicle_params(path); });
  return 0;
}
