#include "sim/params.hpp"

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/params.hpp"

namespace alight::sim {

namespace {

Vector2d read_vec2(const ParamNode& n, const std::string& key, const Vector2d& def) {
  std::array<double, 2> a{def.x(), def.y()};
  n.read(key, a);
  return Vector2d(a[0], a[1]);
}

void read_texture(const ParamNode& n, TextureSpec& t) {
  n.read("kind", t.kind);
  n.read("seed", t.seed);
  n.read("size_px", t.size_px);
  n.read("texel_m", t.texel_m);
  n.read("mean", t.mean);
  n.read("contrast", t.contrast);
  n.read("feature_m", t.feature_m);
  n.read("path", t.path);
  n.validate(t);
  if (t.kind == "image") {
    n.check(!t.path.empty(), "path", "an image texture needs a path");
    t.path = resolve_relative(n.file(), t.path);
    cv::Mat img = cv::imread(t.path, cv::IMREAD_GRAYSCALE);
    if (img.empty()) throw n.error("path", t.path, "cannot read the image file");
    t.image = img;
  }
  n.finish();
}

}  // namespace

VehicleParams load_vehicle_params(const std::string& vehicle_file) {
  const ParamNode root = ParamNode::load_file(vehicle_file);
  const ParamNode n = root.child("vehicle");
  VehicleParams p;
  n.read("name", p.name);
  n.read("mass_kg", p.mass_kg);
  n.read("inertia_kgm2", p.inertia_kgm2);
  n.read("max_thrust_N", p.max_thrust_N);
  n.read("max_tilt_deg", p.max_tilt_deg);
  n.read("max_yaw_rate_dps", p.max_yaw_rate_dps);
  n.read("arm_length_m", p.arm_length_m);
  n.read("rotor_tip_span_m", p.rotor_tip_span_m);
  n.read("gear_footprint_m", p.gear_footprint_m);
  n.read("gear_height_m", p.gear_height_m);
  n.read("rotor_height_m", p.rotor_height_m);
  n.read("motor_tau_s", p.motor_tau_s);
  n.read("attitude_bandwidth_hz", p.attitude_bandwidth_hz);
  n.read("attitude_damping", p.attitude_damping);
  n.read("yaw_bandwidth_hz", p.yaw_bandwidth_hz);
  n.read("max_torque_Nm", p.max_torque_Nm);
  n.read("max_yaw_torque_Nm", p.max_yaw_torque_Nm);
  n.read("drag_linear_Nspm", p.drag_linear_Nspm);
  n.read("drag_quadratic_Ns2pm2", p.drag_quadratic_Ns2pm2);
  n.read("contact_stiffness_Npm", p.contact_stiffness_Npm);
  n.read("contact_damping_Nspm", p.contact_damping_Nspm);
  n.read("friction_coefficient", p.friction_coefficient);
  n.read("cmd_loss_timeout_s", p.cmd_loss_timeout_s);
  n.read("cmd_loss_level_s", p.cmd_loss_level_s);
  n.read("cmd_loss_descent_mps", p.cmd_loss_descent_mps);
  n.read("cmd_loss_disarm_after_s", p.cmd_loss_disarm_after_s);
  n.validate(p);
  n.finish();
  return p;
}

Scenario load_scenario(const std::string& scenario_file) {
  const ParamNode root = ParamNode::load_file(scenario_file);
  Scenario s;
  s.file = scenario_file;
  root.require("name", s.name);
  if (auto n = root.optional_child("sim")) {
    n->read("physics_dt_s", s.physics_dt_s);
    n->read("start_utime", s.start_utime);
    n->finish();
  }
  if (auto n = root.optional_child("area")) {
    s.area_size_m = read_vec2(*n, "size_m", s.area_size_m);
    s.area_center_xy_m = read_vec2(*n, "center_xy_m", s.area_center_xy_m);
    n->read("height_m", s.area_height_m);
    if (auto t = n->optional_child("floor_texture")) read_texture(*t, s.floor_texture);
    n->finish();
  }
  if (auto n = root.optional_child("platform")) {
    PlatformParams p;
    p.center_xy_m = read_vec2(*n, "center_xy_m", p.center_xy_m);
    n->require("size_m", p.size_m);
    n->read("yaw_deg", p.yaw_deg);
    if (auto t = n->optional_child("texture")) read_texture(*t, p.texture);
    n->validate(p);
    n->finish();
    s.platform = p;
  }
  if (auto n = root.optional_child("wall")) {
    WallParams w;
    n->read("x_m", w.x_m);
    n->read("center_y_m", w.center_y_m);
    n->read("width_m", w.width_m);
    n->read("height_m", w.height_m);
    n->read("thickness_m", w.thickness_m);
    n->read("room_depth_m", w.room_depth_m);
    w.has_opening = false;
    if (auto o = n->optional_child("opening")) {
      w.has_opening = true;
      w.opening_center_yz_m = read_vec2(*o, "center_yz_m", w.opening_center_yz_m);
      w.opening_size_m = read_vec2(*o, "size_m", w.opening_size_m);
      o->finish();
    }
    if (auto t = n->optional_child("texture")) read_texture(*t, w.texture);
    if (auto t = n->optional_child("room_texture")) read_texture(*t, w.room_texture);
    n->validate(w);
    n->finish();
    s.wall = w;
  }
  if (auto n = root.optional_child("wind")) {
    n->read("steady_mps", s.wind.steady_mps);
    n->read("gust_sigma_mps", s.wind.gust_sigma_mps);
    n->read("gust_tau_s", s.wind.gust_tau_s);
    n->validate(s.wind);
    n->finish();
  }
  if (auto n = root.optional_child("mocap")) {
    auto& m = s.mocap;
    n->read("rate_hz", m.rate_hz);
    n->read("latency_s", m.latency_s);
    n->read("pos_sigma_m", m.pos_sigma_m);
    n->read("rot_sigma_rad", m.rot_sigma_rad);
    n->read("vel_sigma_mps", m.vel_sigma_mps);
    n->read("rate_sigma_radps", m.rate_sigma_radps);
    n->read("dropout_probability", m.dropout_probability);
    if (n->has("dropouts_s")) {
      const YAML::Node d = n->yaml()["dropouts_s"];
      n->check(d.IsSequence(), "dropouts_s", "must be a list of [start_s, end_s] pairs");
      m.dropouts_s = n->get<std::vector<std::array<double, 2>>>("dropouts_s");
    }
    n->validate(m);
    n->finish();
  }
  if (auto n = root.optional_child("imu")) {
    auto& m = s.imu;
    n->read("rate_hz", m.rate_hz);
    n->read("accel_sigma_mps2", m.accel_sigma_mps2);
    n->read("gyro_sigma_radps", m.gyro_sigma_radps);
    n->read("accel_bias_sigma_mps2", m.accel_bias_sigma_mps2);
    n->read("gyro_bias_sigma_radps", m.gyro_bias_sigma_radps);
    n->validate(m);
    n->finish();
  }
  if (auto n = root.optional_child("camera")) {
    auto& c = s.camera;
    n->read("enabled", c.enabled);
    n->read("mount", c.mount);
    n->read("rate_hz", c.rate_hz);
    n->read("exposure_s", c.exposure_s);
    n->read("latency_s", c.latency_s);
    n->read("noise_sigma", c.noise_sigma);
    n->read("motion_blur_samples", c.motion_blur_samples);
    n->read("gain_jitter", c.gain_jitter);
    n->read("supersample", c.supersample);
    n->validate(c);
    n->finish();
  }
  if (auto n = root.optional_child("lighting")) {
    auto& l = s.lighting;
    n->read("ambient", l.ambient);
    n->read("diffuse", l.diffuse);
    n->read("light_dir_W", l.light_dir_W);
    n->read("gain", l.gain);
    n->read("falloff", l.falloff);
    n->read("lamp_W", l.lamp_W);
    n->read("lamp_radius_m", l.lamp_radius_m);
    n->validate(l);
    n->finish();
  }
  if (auto n = root.optional_child("randomize")) {
    auto& r = s.randomize;
    n->read("platform_xy_m", r.platform_xy_m);
    n->read("platform_yaw_deg", r.platform_yaw_deg);
    n->read("start_clearance_m", r.start_clearance_m);
    n->read("light_gain", r.light_gain);
    n->read("light_dir_deg", r.light_dir_deg);
    n->read("light_falloff", r.light_falloff);
    n->validate(r);
    n->finish();
  }
  if (auto n = root.optional_child("start")) {
    n->read("position_m", s.start_position_m);
    n->read("yaw_deg", s.start_yaw_deg);
    n->finish();
  }
  root.validate(s);
  root.finish();
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
