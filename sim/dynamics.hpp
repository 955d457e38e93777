#pragma once
// Quadrotor rigid-body dynamics with the autopilot's inner attitude loop and contact.
//
// Rigid body: Newton-Euler with thrust along body z, linear + quadratic drag on the airspeed
// (wind), gyroscopic coupling; semi-implicit Euler at a fixed step (1 kHz or finer).
// Inner loop: the geometric attitude error of Lee, Leok and McClamroch ("Geometric tracking
// control of a quadrotor UAV on SE(3)", CDC 2010), e_R = 1/2 vee(R_d^T R - R^T R_d), with PD
// gains from the loop's natural frequency and damping and torque saturation, tracking roll,
// pitch (Z-Y-X Euler, as ATTITUDE_CMD defines them) and an integrated yaw-rate command; the
// collective thrust follows the command through a first-order motor lag. Disarmed motors give
// no thrust and no torque at once.
// Contact: penalty springs and dampers with Coulomb friction at the four gear feet and at points
// on the rotor rims, against the floor and the scene's boxes; a point inside a box is pushed out
// through the face it is least deep behind, so gear over the platform top rests on it and gear
// past its edge does not (and tips the vehicle off). A moving box (Box::v_W, omega_W: a
// platform's deck) acts with the velocity of its surface, so a vehicle standing on it is
// carried by friction and an impact is judged by the speed relative to the deck.

#include <cstdint>

#include "sim/params.hpp"
#include "sim/scene.hpp"

namespace alight::sim {

/// What the outer loop commands (domain form of attitude_cmd_t).
struct AttitudeCommand {
  int64_t utime = 0;
  double roll_rad = 0.0;
  double pitch_rad = 0.0;
  double yaw_rate_radps = 0.0;  ///< about world z
  double thrust_N = 0.0;
  bool armed = false;
  bool forced = false;  ///< a disarm the autopilot takes in the air (the operator's signed KILL)
};

struct VehicleState {
  Vector3d p_W_B = Vector3d::Zero();           ///< body origin in world [m]
  Vector3d v_W_B = Vector3d::Zero();           ///< [m/s]
  Quaterniond q_WB = Quaterniond::Identity();  ///< body to world
  Vector3d omega_B = Vector3d::Zero();         ///< [rad/s]
  double thrust_N = 0.0;                       ///< current collective thrust (after motor lag)
  double yaw_des_rad = 0.0;                    ///< inner loop's integrated yaw reference
  bool armed = false;
};

/// What touches what in one step.
enum class Contact {
  kNone = 0,
  kFloor = 1,
  kPlatformTop = 2,
  kPlatformEdge = 3,
  kWall = 4,
  kFrame = 5
};

struct StepResult {
  Vector3d specific_force_B =
      Vector3d::Zero();              ///< non-gravitational force / mass, in body [m/s^2]
  Contact contact = Contact::kNone;  ///< the most severe contact this step
  int feet_on_platform_top = 0;      ///< gear feet resting on the platform top
  bool rim_touch = false;            ///< a rotor rim touched the floor or platform (on its side)
};

class Dynamics {
 public:
  Dynamics(const VehicleParams& vehicle, const Scene& scene);

  /// Advances `state` by dt_s under `cmd`, with `wind_W` [m/s].
  StepResult step(VehicleState& state, const AttitudeCommand& cmd, const Vector3d& wind_W,
                  double dt_s) const;

  /// What the vehicle touches in `state`, without moving it: for a state that comes from another
  /// simulator (Simulator::follow). A point up to `margin_m` above the floor or a box's top
  /// counts as touching it. specific_force_B is left zero.
  StepResult contacts(const VehicleState& state, double margin_m = 0.0) const;
  /// Body height of a level vehicle resting with its gear on a surface at height z [m].
  double resting_height(double surface_z_m) const;
  /// Inner-loop torque for a command (exposed for tests) [N m, body].
  Vector3d attitude_torque(const VehicleState& state, const AttitudeCommand& cmd) const;
  const VehicleParams& vehicle() const { return vehicle_; }

 private:
  // Calls visit(outward normal, depth, contact, the surface's velocity there) for the floor and
  // each box a point is inside of (boxes widened upwards by margin_m), in a fixed order.
  template <class F>
  void penetrations(const Vector3d& p_W, double margin_m, F&& visit) const;

  VehicleParams vehicle_;
  const Scene& scene_;
  std::vector<Vector3d> feet_B_;
  std::vector<Vector3d> rim_B_;
};

}  // namespace alight::sim
