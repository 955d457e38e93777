#pragma once
// The vehicle's true state from an autopilot's own simulator, for alight-sim as a
// sensor renderer (alight-sim --truth-from): ArduPilot SITL's SIM_STATE (libraries/SITL/SITL.cpp,
// sim_state_send) or PX4 SIH's HIL_STATE_QUATERNION (src/modules/mavlink/streams/
// HIL_STATE_QUATERNION.hpp, read from SIH's ground-truth topics), over MAVLink, in alight's world.
// Pure: bytes and the time go in, bytes to send and states come out.
//
// The world: the first sample is the vehicle at rest at the scenario's start (`start_W`,
// `start_yaw_rad`); the autopilot's local tangent plane about that sample (north, east, down) is
// turned about the vertical so that the heading there is the start yaw. Positions arrive as
// latitude and longitude in 1e-7 degrees (1.1 cm north; ArduPilot's float lat / lon hold degE7
// and are coarser still, so lat_int / lon_int are read), velocities finer (ArduPilot: float m/s;
// PX4: cm/s): the position is the integral of the velocity pulled toward the quantised position
// with time constant position_tau_s, so that the rendered camera and motion capture do not step
// by a centimetre. Neither message carries a usable time (SIM_STATE has none, PX4 leaves
// time_usec 0): a sample is stamped when it arrived (the kernel's receipt time), and raw_at()
// extrapolates the newest with its velocity and body rates. A SITL on a loaded machine sends its
// states late and in bursts, so that raw trajectory steps by millimetres and tenths of a degree
// from sample to sample; the renderer's camera and motion capture (sampled at 100 Hz and
// interpolated by the vision) would then disagree by as much. advance() is what the renderer
// uses: a trajectory that tracks raw_at() smoothly (position: second order with the raw velocity
// fed forward, smooth_hz; attitude: the raw body rates fed forward plus attitude_gain_per_s times
// the attitude error), whose velocity and body rates are its own motion. The autopilot's
// HEARTBEAT gives the armed state.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/geometry.hpp"
#include "mavlink/autopilot_modes.hpp"
#include "mavlink/frame.hpp"
#include "mavlink/parser.hpp"
#include "sim/dynamics.hpp"

namespace alight::sim {

struct AutopilotTruthParams {
  mavlink::Flavour flavour = mavlink::Flavour::kArdupilot;
  Vector3d start_W = Vector3d::Zero();  ///< body origin at rest at the start, world [m]
  double start_yaw_rad = 0.0;           ///< heading at the start, world (from x, about z up)
  double rate_hz = 100.0;               ///< truth messages asked of the autopilot [Hz]
  double position_tau_s = 1.0;          ///< pull of the quantised position [s]
  /// raw_at() extrapolates the newest sample this far: three periods of the asked rate. PX4 SIH's
  /// lockstep clock stalls on a loaded machine; extrapolated on the wall clock through a stall,
  /// motion capture ran ahead of the vehicle and EKF2 fused a pose 5 cm off.
  double max_extrapolation_s = 0.03;
  double smooth_hz = 8.0;             ///< advance(): natural frequency of the position [Hz]
  double attitude_gain_per_s = 30.0;  ///< advance(): pull of the attitude error [1/s]
  uint8_t own_sysid = 200, own_compid = 190;
};

struct TruthSample {
  int64_t utime = 0;  ///< when it was received
  VehicleState state;
};

class AutopilotTruth {
 public:
  explicit AutopilotTruth(const AutopilotTruthParams& params);

  struct Output {
    std::vector<uint8_t> bytes;        ///< to the autopilot
    std::vector<TruthSample> samples;  ///< new samples, in order
    std::vector<std::string> events;
  };
  Output update(std::span<const uint8_t> bytes, int64_t now_utime);

  /// The vehicle at `t`: the newest sample extrapolated (at most max_extrapolation_s), or the
  /// resting start before any sample.
  VehicleState raw_at(int64_t t) const;
  /// The smoothed vehicle at `t` (not before the previous call's time): see above.
  VehicleState advance(int64_t t);
  bool has_sample() const { return last_.has_value(); }
  int64_t last_sample_utime() const { return last_ ? last_->utime : 0; }
  bool armed() const { return armed_; }
  /// HEARTBEAT.custom_mode (its changes are reported as events: the failsafes' record).
  uint32_t custom_mode() const { return custom_mode_; }
  uint64_t samples() const { return n_samples_; }
  uint64_t rejected() const { return n_rejected_; }
  const mavlink::ParserStats& parser_stats() const { return parser_.stats(); }

  /// Local north / east offsets [m] of a geodetic position from a reference, as the autopilot
  /// computes them (ArduPilot: libraries/AP_Common/Location.cpp, 0.011131884502145034 m per
  /// 1e-7 degree of latitude, longitude scaled by the cosine of the mean latitude; PX4:
  /// src/lib/geo, a sphere of radius 6371 km about the reference).
  static Vector2d north_east_m(mavlink::Flavour flavour, int32_t lat_e7, int32_t lon_e7,
                               int32_t ref_lat_e7, int32_t ref_lon_e7);

 private:
  struct Raw {
    int32_t lat_e7 = 0, lon_e7 = 0;
    double alt_m = 0;
    Vector3d v_NED = Vector3d::Zero();
    Quaterniond q_NED_FRD = Quaterniond::Identity();
    Vector3d omega_FRD = Vector3d::Zero();
  };
  void on_sample(const Raw& r, int64_t now, Output& out);
  template <class M>
  void send(const M& m, int64_t now, Output& out);

  AutopilotTruthParams params_;
  mavlink::Parser parser_;
  mavlink::Sender sender_;
  std::optional<uint8_t> sysid_;
  bool armed_ = false, heard_ = false;
  int heartbeat_asks_ = 0;
  uint32_t custom_mode_ = 0;
  int64_t next_request_ = 0, next_heartbeat_ = 0;
  // The anchor: the first sample.
  std::optional<Raw> anchor_;
  Matrix3d R_W_ENU_ = Matrix3d::Identity();  // turns the autopilot's ENU into the world
  // The filtered local position (NED about the anchor) and the last sample.
  Vector3d p_NED_ = Vector3d::Zero();
  Vector3d v_prev_NED_ = Vector3d::Zero();
  std::optional<TruthSample> last_;
  std::optional<VehicleState> smooth_;
  int64_t smooth_utime_ = 0;
  uint64_t n_samples_ = 0, n_rejected_ = 0;
};

}  // namespace alight::sim
