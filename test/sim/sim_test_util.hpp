#pragma once
// Shared set-up of the simulator tests: the repository's scenario and vehicle files.

#include <string>

#include "common/build_paths.hpp"
#include "sim/params.hpp"
#include "sim/simulator.hpp"

namespace alight::sim::test {

inline std::string config_path(const std::string& rel) {
  return std::string(alight::build::source_dir()) + "/config/" + rel;
}
inline Scenario scenario(const std::string& name) {
  return load_scenario(config_path("scenarios/" + name + ".yaml"));
}
inline VehicleParams starmac() { return load_vehicle_params(config_path("vehicles/starmac.yaml")); }

/// A scenario without randomisation, noise-free sensors, so a test controls every number.
inline Scenario quiet(Scenario s) {
  s.randomize = RandomizeParams{};
  s.camera.enabled = false;
  return s;
}

/// Hover command for the vehicle (level, thrust = weight).
inline AttitudeCommand hover(const VehicleParams& v) {
  AttitudeCommand c;
  c.armed = true;
  c.thrust_N = v.hover_thrust_N();
  return c;
}

/// Places the vehicle level at p_W, at rest, motors at hover thrust.
inline void place(Simulator& sim, const Vector3d& p_W, bool armed = true, double yaw = 0.0) {
  VehicleState s;
  s.p_W_B = p_W;
  s.q_WB = Quaterniond(rotation_from_rpy(0, 0, yaw));
  s.yaw_des_rad = yaw;
  s.armed = armed;
  s.thrust_N = armed ? sim.dynamics().vehicle().hover_thrust_N() : 0.0;
  sim.set_state(s);
}

}  // namespace alight::sim::test
