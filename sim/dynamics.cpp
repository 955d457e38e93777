#include "sim/dynamics.hpp"

#include <algorithm>
#include <cmath>

namespace alight::sim {

namespace {
constexpr double kG = 9.81;

Vector3d vee(const Matrix3d& S) { return Vector3d(S(2, 1), S(0, 2), S(1, 0)); }

// Contact spring at a point penetrating a surface with outward normal n_W by depth pen: normal
// force (never pulling) and Coulomb-limited viscous friction.
Vector3d contact_force(const Vector3d& n_W, double pen, const Vector3d& v_point_W,
                       const VehicleParams& p) {
  const double vn = v_point_W.dot(n_W);
  const double fn = std::max(0.0, p.contact_stiffness_Npm * pen - p.contact_damping_Nspm * vn);
  const Vector3d vt = v_point_W - vn * n_W;
  Vector3d ft = -p.contact_damping_Nspm * 2.0 * vt;
  const double ft_max = p.friction_coefficient * fn;
  if (ft.norm() > ft_max) ft *= ft_max / ft.norm();
  return fn * n_W + ft;
}
}  // namespace

Dynamics::Dynamics(const VehicleParams& vehicle, const Scene& scene)
    : vehicle_(vehicle), scene_(scene) {
  const double g = 0.5 * vehicle.gear_footprint_m;
  for (int i = 0; i < 4; ++i)
    feet_B_.emplace_back((i & 1 ? g : -g), (i & 2 ? g : -g), -vehicle.gear_height_m);
  const double r = 0.5 * vehicle.rotor_tip_span_m;
  for (int i = 0; i < 16; ++i) {
    const double a = 2 * M_PI * i / 16.0;
    rim_B_.emplace_back(r * std::cos(a), r * std::sin(a), vehicle.rotor_height_m);
  }
  rim_B_.emplace_back(0, 0, vehicle.rotor_height_m + 0.03);  // top of the body
}

template <class F>
void Dynamics::penetrations(const Vector3d& p_W, double margin_m, F&& visit) const {
  if (p_W.z() < margin_m)
    visit(Vector3d::UnitZ(), margin_m - p_W.z(), Contact::kFloor, Vector3d::Zero());
  for (const Box& b : scene_.boxes) {
    if ((p_W - b.center_W).cwiseAbs().maxCoeff() > b.half_size_m.maxCoeff() * 1.7321 + margin_m)
      continue;
    const Vector3d q = b.to_local(p_W);
    // The margin widens the box upwards only: a point that close above its top touches it.
    Vector3d depth = b.half_size_m - q.cwiseAbs();
    if (q.z() > 0) depth.z() += margin_m;
    if (depth.minCoeff() <= 0.0) continue;
    int a;
    const double pen = depth.minCoeff(&a);
    Vector3d n_O = Vector3d::Zero();
    n_O[a] = q[a] >= 0 ? 1.0 : -1.0;
    Contact c;
    if (b.kind == Box::Kind::kPlatform)
      c = a == 2 && q.z() > 0 ? Contact::kPlatformTop : Contact::kPlatformEdge;
    else
      c = scene_.near_opening_frame(p_W) ? Contact::kFrame : Contact::kWall;
    visit(b.R_WO() * n_O, pen, c, b.moving ? Vector3d(b.velocity_at(p_W)) : Vector3d::Zero());
  }
}

StepResult Dynamics::contacts(const VehicleState& s, double margin_m) const {
  StepResult res;
  const Matrix3d R = s.q_WB.toRotationMatrix();
  int severity = 0;
  auto check = [&](const Vector3d& r_B, bool is_foot) {
    bool ground = false;
    penetrations(
        s.p_W_B + R * r_B, margin_m, [&](const Vector3d&, double, Contact c, const Vector3d&) {
          severity = std::max(severity, static_cast<int>(c));
          if (c == Contact::kFloor || c == Contact::kPlatformTop || c == Contact::kPlatformEdge)
            ground = true;
          if (c == Contact::kPlatformTop && is_foot) ++res.feet_on_platform_top;
        });
    if (ground && !is_foot) res.rim_touch = true;
  };
  for (const auto& r : feet_B_) check(r, true);
  for (const auto& r : rim_B_) check(r, false);
  res.contact = static_cast<Contact>(severity);
  return res;
}

double Dynamics::resting_height(double surface_z_m) const {
  // Feet sink until the springs carry the weight.
  const double pen = vehicle_.mass_kg * kG / (4.0 * vehicle_.contact_stiffness_Npm);
  return surface_z_m + vehicle_.gear_height_m - pen;
}

Vector3d Dynamics::attitude_torque(const VehicleState& s, const AttitudeCommand& cmd) const {
  const double tilt_max = vehicle_.max_tilt_deg * M_PI / 180.0;
  const double roll = std::clamp(cmd.roll_rad, -tilt_max, tilt_max);
  const double pitch = std::clamp(cmd.pitch_rad, -tilt_max, tilt_max);
  const Matrix3d R = s.q_WB.toRotationMatrix();
  const Matrix3d R_d = rotation_from_rpy(roll, pitch, s.yaw_des_rad);
  const Vector3d e_R = 0.5 * vee(R_d.transpose() * R - R.transpose() * R_d);
  const double yaw_rate_max = vehicle_.max_yaw_rate_dps * M_PI / 180.0;
  const double r_cmd = std::clamp(cmd.yaw_rate_radps, -yaw_rate_max, yaw_rate_max);
  const Vector3d omega_d = R.transpose() * Vector3d(0, 0, r_cmd);
  const Vector3d e_w = s.omega_B - omega_d;
  const double wn = 2 * M_PI * vehicle_.attitude_bandwidth_hz, z = vehicle_.attitude_damping;
  const double wy = 2 * M_PI * vehicle_.yaw_bandwidth_hz;
  const Vector3d& J = vehicle_.inertia_kgm2;
  Vector3d tau(J.x() * (-wn * wn * e_R.x() - 2 * z * wn * e_w.x()),
               J.y() * (-wn * wn * e_R.y() - 2 * z * wn * e_w.y()),
               J.z() * (-wy * wy * e_R.z() - 2 * z * wy * e_w.z()));
  tau.x() = std::clamp(tau.x(), -vehicle_.max_torque_Nm, vehicle_.max_torque_Nm);
  tau.y() = std::clamp(tau.y(), -vehicle_.max_torque_Nm, vehicle_.max_torque_Nm);
  tau.z() = std::clamp(tau.z(), -vehicle_.max_yaw_torque_Nm, vehicle_.max_yaw_torque_Nm);
  return tau;
}

StepResult Dynamics::step(VehicleState& s, const AttitudeCommand& cmd, const Vector3d& wind_W,
                          double dt) const {
  const VehicleParams& p = vehicle_;
  StepResult res;
  const Matrix3d R = s.q_WB.toRotationMatrix();

  // Inner loop and motors.
  s.armed = cmd.armed;
  Vector3d tau_B = Vector3d::Zero();
  if (s.armed) {
    const double yaw_rate_max = p.max_yaw_rate_dps * M_PI / 180.0;
    s.yaw_des_rad = wrap_angle(s.yaw_des_rad +
                               std::clamp(cmd.yaw_rate_radps, -yaw_rate_max, yaw_rate_max) * dt);
    tau_B = attitude_torque(s, cmd);
    const double target = std::clamp(cmd.thrust_N, 0.0, p.max_thrust_N);
    s.thrust_N = p.motor_tau_s > 0
                     ? s.thrust_N + (target - s.thrust_N) * std::min(1.0, dt / p.motor_tau_s)
                     : target;
  } else {
    s.thrust_N = 0.0;
    s.yaw_des_rad = yaw_of(R);  // re-arming holds the current heading
  }

  Vector3d F_W = R.col(2) * s.thrust_N;
  const Vector3d v_air = s.v_W_B - wind_W;
  F_W += -p.drag_linear_Nspm * v_air - p.drag_quadratic_Ns2pm2 * v_air.norm() * v_air;

  // Contacts.
  int severity = 0;
  auto touch = [&](Contact c) { severity = std::max(severity, static_cast<int>(c)); };
  auto apply = [&](const Vector3d& r_B, bool is_foot) {
    const Vector3d p_W = s.p_W_B + R * r_B;
    const Vector3d v_W = s.v_W_B + R * s.omega_B.cross(r_B);
    Vector3d f = Vector3d::Zero();
    bool ground = false;  // floor or platform, not the wall
    penetrations(p_W, 0.0, [&](const Vector3d& n_W, double pen, Contact c, const Vector3d& v_S) {
      // A moving surface (a platform's deck) pushes and drags with its own velocity: what
      // counts at the contact is the speed relative to it.
      f += contact_force(n_W, pen, v_W - v_S, p);
      touch(c);
      if (c == Contact::kFloor || c == Contact::kPlatformTop || c == Contact::kPlatformEdge)
        ground = true;
      if (c == Contact::kPlatformTop && is_foot) ++res.feet_on_platform_top;
    });
    if (ground && !is_foot) res.rim_touch = true;
    F_W += f;
    tau_B += r_B.cross(R.transpose() * f);
  };
  for (const auto& r : feet_B_) apply(r, true);
  for (const auto& r : rim_B_) apply(r, false);
  res.contact = static_cast<Contact>(severity);

  res.specific_force_B = R.transpose() * (F_W / p.mass_kg);

  // Semi-implicit Euler: velocities first, then positions with the new velocities.
  const Vector3d a_W = F_W / p.mass_kg - Vector3d(0, 0, kG);
  s.v_W_B += a_W * dt;
  s.p_W_B += s.v_W_B * dt;
  const Vector3d& J = p.inertia_kgm2;
  const Vector3d Jw = J.cwiseProduct(s.omega_B);
  const Vector3d alpha = (tau_B - s.omega_B.cross(Jw)).cwiseQuotient(J);
  s.omega_B += alpha * dt;
  const Vector3d dtheta = s.omega_B * dt;
  const double angle = dtheta.norm();
  if (angle > 0)
    s.q_WB = (s.q_WB * Quaterniond(Eigen::AngleAxisd(angle, dtheta / angle))).normalized();
  return res;
}

}  // namespace alight::sim
