#pragma once
// Parameters of alight-mocap: the `mocap:` section of a motion-capture file (config/mocap/*.yaml).
// Which server and object, how the room's frame and units become alight's world frame (z up,
// metres; docs/ARCHITECTURE.md "Frames"), where the vehicle's body frame sits in the tracked
// object's frame, how stamps and velocities are made, and how the connection is kept.

#include <Eigen/Core>
#include <optional>
#include <string>

#include "common/channels.hpp"
#include "common/param_schema.hpp"

namespace alight::mocap {

/// `Object@host` or `Object@host:port` (VRPN's device naming).
struct TrackerAddress {
  std::string object;  ///< the tracker's sender name, e.g. "Pelican"
  std::string host;    ///< name or address of the server
  int port = 3883;
};
/// Parses a tracker address; nullopt when it is not of that form (empty parts, bad port).
std::optional<TrackerAddress> parse_tracker(const std::string& text);

struct ServerParams {
  std::string tracker;  ///< "Object@host[:port]"
  int sensor = 0;       ///< sensor of that tracker (0 for a VICON / Motive / QTM rigid body)
  double connect_timeout_s = 1.0;  ///< one TCP connection attempt [s]
  double silence_timeout_s = 2.0;  ///< connected but no byte for this long: reconnect [s]
  double retry_initial_s = 0.1;    ///< first reconnection delay; doubles up to retry_max_s [s]
  double retry_max_s = 2.0;        ///< [s]
  double start_timeout_s =
      0.0;  ///< never connected this long after start: exit 3 (0: retry forever) [s]
  static const ParamSchema<ServerParams>& schema();
};

struct RoomParams {
  std::string units = "m";    ///< unit of the server's positions: "m" or "mm"
  std::string up_axis = "z";  ///< the room's up axis: "z" (VICON, QTM) or "y" (Motive's default)
  double yaw_deg = 0.0;  ///< world yaw of the levelled room axes (rotation about world z) [deg]
  Eigen::Vector3d p_W_R_m = Eigen::Vector3d::Zero();  ///< room origin in world [m]
  static const ParamSchema<RoomParams>& schema();
};

struct BodyParams {
  /// R_MB as roll, pitch, yaw (Z-Y-X, rotation_from_rpy): the vehicle's body axes (x forward,
  /// y left, z up) in the tracked object's frame M [deg].
  Eigen::Vector3d rpy_M_B_deg = Eigen::Vector3d::Zero();
  Eigen::Vector3d t_M_B_m = Eigen::Vector3d::Zero();  ///< body origin in M [m]
  static const ParamSchema<BodyParams>& schema();
};

struct StampParams {
  /// "server": the server's stamps as they are (clocks synchronised, e.g. by PTP or chrony);
  /// "mapped": the server's stamps moved onto our clock by the smallest receipt delay seen
  /// (keeps the server's sample spacing, absorbs any clock offset); "receive": our receipt time.
  std::string source = "mapped";
  double latency_s = 0.0;  ///< known delay from sample to what the stamp stands for, subtracted [s]
  double offset_window_s = 10.0;    ///< "mapped": the smallest delay is taken over this long [s]
  double max_clock_offset_s = 0.5;  ///< "server": stamps further from our clock are refused [s]
  static const ParamSchema<StampParams>& schema();
};

struct VelocityParams {
  /// "finite_difference": from the poses; "server": the server's Velocity messages (linear part;
  /// the angular rate is always differenced), a pose waiting at most for the next one.
  std::string source = "finite_difference";
  double span_s = 0.01;    ///< difference over at least this much time (noise at high rates) [s]
  double max_gap_s = 0.1;  ///< no difference across a larger gap: that pose is held back [s]
  static const ParamSchema<VelocityParams>& schema();
};

struct MocapParams {
  ServerParams server;
  RoomParams room;
  BodyParams body;
  StampParams stamp;
  VelocityParams velocity;
  std::string channel = channels::kMocapPose;  ///< pose_t output

  static const ParamSchema<MocapParams>& schema();
  void validate() const;  ///< throws ParamError naming the field and its value
};

/// Reads the `mocap:` section of a file whose only top-level key it is.
MocapParams load_params(const std::string& file);
MocapParams load_params(const ParamNode& root);

}  // namespace alight::mocap
