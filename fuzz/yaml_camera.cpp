// Camera files: the camera driver's parameters (config/cameras/usb_*.yaml and the like, with the
// camera_info they name) and camera_info files (ROS layout, config/cameras/firefly_mv_4mm.yaml)
// as vision, the simulator and the driver read them. Both loaders see every input.
#include "camera_driver/params.hpp"
#include "common/camera_model.hpp"
#include "fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  static fuzz::InputFile file("camera");
  const std::string& path = file.write(data, size);
  fuzz::expect_param_errors_only("load_camera_info", [&] { load_camera_info(path); });
  fuzz::expect_param_errors_only("camera::load_params", [&] {
    const camera::CameraParams p = camera::load_params(path);
    (void)camera::capture_config(p);
    (void)camera::supervisor_params(p);
    load_camera_info(p.camera_info);  // as alight-camera does at start
  });
  return 0;
}
