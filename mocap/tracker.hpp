#pragma once
// A VRPN tracker client without sockets or clocks: the node feeds it the bytes of one TCP
// connection with their receipt time and publishes what it returns. It picks the configured
// object and sensor out of the stream (mocap/vrpn.hpp), refuses unusable values and stamps, puts
// the pose in world (mocap/room_frame.hpp), stamps it on our clock (ClockMap) and adds the
// velocities (finite differences, or the server's linear velocity when configured).

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "common/pose_buffer.hpp"
#include "mocap/params.hpp"
#include "mocap/room_frame.hpp"
#include "mocap/vrpn.hpp"

namespace alight::mocap {

/// Server stamps onto our clock (StampParams::source). Times in microseconds; `recv_utime` is
/// our wall clock when the bytes arrived.
class ClockMap {
 public:
  explicit ClockMap(const StampParams& params);
  /// Notes one server stamp received at recv_utime ("mapped": the delay it shows).
  void observe(int64_t server_us, int64_t recv_utime);
  /// Our utime for a server stamp received at recv_utime, in a read whose newest server stamp
  /// was read_newest_us; nullopt (and *why) when refused. "receive" stamps the newest report of
  /// a read with the receipt time and earlier ones of the same read with the server's spacing
  /// before it, so that poses read together keep distinct, increasing stamps.
  std::optional<int64_t> to_local(int64_t server_us, int64_t recv_utime, int64_t read_newest_us,
                                  std::string* why) const;
  /// The offset "mapped" adds to server stamps (smallest recv - server in the window) [us].
  std::optional<int64_t> offset_us() const;
  void reset() { window_.clear(); }

 private:
  StampParams params_;
  // (recv_utime, recv - server) with increasing offsets: the front is the window's minimum.
  std::deque<std::pair<int64_t, int64_t>> window_;
};

/// One pose to publish.
struct TrackerPose {
  PoseSample pose;        ///< body in world; utime on our clock
  int64_t server_us = 0;  ///< the server's stamp
  int64_t delay_us = 0;   ///< receipt - server stamp (a latency only with synchronised clocks)
  bool server_velocity = false;  ///< pose.v_W_B is the server's, not a difference
};

struct TrackerStats {
  vrpn::DecoderStats decoder;
  uint64_t reports = 0;           ///< reports of the configured object and sensor
  uint64_t other_objects = 0;     ///< reports of other trackers or sensors (not an error)
  uint64_t rejected_values = 0;   ///< non-finite numbers, a quaternion whose norm is not 1
  uint64_t rejected_stamps = 0;   ///< not after the previous one, or far from our clock
  uint64_t held_back = 0;         ///< first pose of a track or after a gap: no velocity yet
  uint64_t velocity_missing = 0;  ///< velocity.source server, but no Velocity came for a pose
  uint64_t poses = 0;             ///< returned for publishing
  uint64_t truncated = 0;         ///< connections that ended inside a message
  std::string last_refusal;       ///< why the last value or stamp was refused
};

class TrackerClient {
 public:
  explicit TrackerClient(const MocapParams& params);

  /// What the client sends after connecting: its cookie, then a description of the object it
  /// listens to and of the tracker message types, as VRPN clients do.
  std::vector<uint8_t> greeting(int64_t wall_utime) const;

  /// A new connection: a fresh stream (ids are per connection) and clock estimate, no history.
  void reset();
  /// The connection ended; counts a message it cut off.
  void end_of_stream();

  /// Bytes of the connection received at recv_utime (our wall clock). Returns the poses they
  /// completed, oldest first.
  std::vector<TrackerPose> on_bytes(const uint8_t* data, size_t size, int64_t recv_utime);

  /// The stream is unusable (not VRPN, out of step): reconnect.
  bool failed() const { return decoder_.failed(); }
  const std::string& error() const { return decoder_.error(); }
  const vrpn::StreamDecoder& decoder() const { return decoder_; }
  /// Counters over every connection so far.
  TrackerStats stats() const;
  const RoomFrame& frame() const { return frame_; }
  /// Names of the trackers the server sent reports of (the first 16), for telling an operator
  /// which objects there are when the configured one is not among them.
  const std::vector<std::string>& trackers_seen() const { return trackers_seen_; }

 private:
  struct Sample {
    int64_t utime;
    Vector3d p_W_B;
    Quaterniond q_WB;
  };
  bool refuse_value(const std::string& why);
  void on_pose(const vrpn::TrackerReport& r, int64_t recv_utime, int64_t read_newest_us,
               std::vector<TrackerPose>& out);
  void on_velocity(const vrpn::TrackerReport& r, std::vector<TrackerPose>& out);
  void apply_server_velocity(TrackerPose& pose, const vrpn::TrackerReport& velocity) const;
  /// Adds the differenced velocities to `pose` from the history; false when there is none.
  bool difference(TrackerPose& pose);

  MocapParams params_;
  TrackerAddress address_;
  RoomFrame frame_;
  ClockMap clock_;
  vrpn::StreamDecoder decoder_;
  vrpn::DecoderStats finished_;  // decoder counters of earlier connections
  TrackerStats stats_;
  std::deque<Sample> history_;   // accepted poses, oldest first, for the differences
  int64_t last_server_us_ = -1;  // per connection: stamps must increase
  int64_t last_utime_ = 0;       // over connections: published stamps must increase
  // velocity.source server: a pose waiting for its Velocity, a Velocity that came first.
  std::optional<TrackerPose> waiting_;
  std::optional<vrpn::TrackerReport> early_velocity_;
  std::vector<std::string> trackers_seen_;
};

}  // namespace alight::mocap
