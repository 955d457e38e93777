#include "sim/params.hpp"

#include <opencv2/imgcodecs.hpp>

#include "common/params.hpp"

namespace alight::sim {

namespace {

// An image texture's pixels, after the schema resolved and checked its path; `key` is the
// texture's dotted key in the file.
void load_image(TextureSpec& t, const std::string& file, const std::string& key) {
  if (t.kind != "image") return;
  t.image = cv::imread(t.path, cv::IMREAD_GRAYSCALE);
  if (t.image.empty()) throw ParamError(file, key + ".path", t.path, "cannot read the image file");
}

}  // namespace

VehicleParams load_vehicle_params(const std::string& vehicle_file) {
  const ParamNode root = ParamNode::load_file(vehicle_file);
  VehicleParams p;
  VehicleParams::schema().read(root.child("vehicle"), p);
  return p;
}

Scenario load_scenario(const std::string& scenario_file) {
  const ParamNode root = ParamNode::load_file(scenario_file);
  Scenario s;
  Scenario::schema().read(root, s);
  s.file = scenario_file;
  load_image(s.floor_texture, scenario_file, "area.floor_texture");
  if (s.platform) {
    load_image(s.platform->texture, scenario_file, "platform.texture");
    if (s.platform->reflective)
      load_image(s.platform->reflection.sky, scenario_file, "platform.reflection.sky");
  }
  if (s.wall) {
    load_image(s.wall->texture, scenario_file, "wall.texture");
    load_image(s.wall->room_texture, scenario_file, "wall.room_texture");
  }
  return s;
}

CameraRig load_camera_rig(const std::string& vehicle_file, const std::string& mount_name) {
  const ParamNode root = ParamNode::load_file(vehicle_file);
  CameraRig rig;
  rig.mount = load_camera_mount(root, mount_name);
  rig.model = load_camera_info(rig.mount.camera_info_path);
  return rig;
}

}  // namespace alight::sim
