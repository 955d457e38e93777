#pragma once
// A VRPN tracker server for tests and benchmarks, written from VRPN's protocol description
// (Format_Of_Protocol.txt: cookie, header, sender and type descriptions) and the tracker
// messages' layout, and deliberately sharing no code with the client in mocap/: a symmetric
// mistake (byte order, quaternion order, padding) would otherwise pass unnoticed. It serves
// poses the caller gives it, over TCP on 127.0.0.1 only, to one client at a time, and can send
// what a broken server sends (garbage, truncated messages, undescribed ids).
//
// Blocking, single-threaded; a test streams from a thread of its own.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace alight::tools {

struct VrpnServerOptions {
  std::string version = "07.35";  ///< "MM.mm" in the cookie
  int port = 0;                   ///< 0: any free port
  /// The ids this server gives its senders and types. VRPN ids are each peer's own: starting
  /// elsewhere than 0 catches a client that takes the server's ids for its own.
  int32_t first_sender_id = 3;
  int32_t first_type_id = 5;
};

/// One tracker report as the server sends it: room frame, room units, quaternion x y z w.
struct ServedPose {
  std::string object;
  int32_t sensor = 0;
  int64_t stamp_us = 0;  ///< header timestamp [us since the Unix epoch]
  double pos[3] = {0, 0, 0};
  double quat_xyzw[4] = {0, 0, 0, 1};
};

class VrpnTestServer {
 public:
  explicit VrpnTestServer(VrpnServerOptions options = {});
  ~VrpnTestServer();
  VrpnTestServer(const VrpnTestServer&) = delete;
  VrpnTestServer& operator=(const VrpnTestServer&) = delete;

  /// Listens on 127.0.0.1 at options.port, or at the port it had before when it is listening
  /// again after close() (a restarted server). False on failure.
  bool listen();
  int port() const { return port_; }
  /// Waits up to timeout_s for a client; sends our cookie, checks the client's, and describes
  /// `objects` and the tracker types (with a few types a tracker client must ignore).
  bool accept(double timeout_s, const std::vector<std::string>& objects);
  bool connected() const { return client_ >= 0; }
  /// The client's cookie as received (24 bytes).
  const std::vector<uint8_t>& client_cookie() const { return client_cookie_; }
  /// Reads what the client sent after its cookie for up to timeout_s; returns the names it
  /// described (senders and types), or what it has so far.
  std::vector<std::string> client_descriptions(double timeout_s);

  bool send_pose(const ServedPose& pose);
  /// A "vrpn_Tracker Velocity" report: linear velocity [room units / s], no rotation.
  bool send_velocity(const std::string& object, int32_t sensor, int64_t stamp_us,
                     const double vel[3]);
  bool send_raw(const std::vector<uint8_t>& bytes);
  /// A framed message of any type and sender id (for refusals); payload padded to 8 bytes.
  static std::vector<uint8_t> frame(int32_t type, int32_t sender, int64_t stamp_us,
                                    const std::vector<uint8_t>& payload);
  /// Payload of a Pos_Quat report.
  static std::vector<uint8_t> pose_payload(const ServedPose& pose);
  int32_t sender_id(const std::string& object) const;
  int32_t type_id(const std::string& name) const;

  /// Closes the client's connection (the server stays up).
  void drop_client();
  /// Closes the client and stops listening (a stopped server).
  void close();
  /// Bytes sent to clients so far.
  uint64_t bytes_sent() const { return bytes_sent_; }

 private:
  bool write_all(const uint8_t* data, size_t size);
  bool read_exact(uint8_t* data, size_t size, double timeout_s);

  VrpnServerOptions options_;
  int listener_ = -1;
  int client_ = -1;
  int port_ = 0;
  std::vector<uint8_t> client_cookie_;
  std::vector<uint8_t> client_bytes_;
  std::map<std::string, int32_t> senders_, types_;
  uint64_t bytes_sent_ = 0;
};

}  // namespace alight::tools
