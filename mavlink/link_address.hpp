#pragma once
// Where alight-mavlink meets the autopilot, as one string (the `mavlink.link` parameter and
// --link):
//
//   serial:/dev/ttyACM0:921600      a UART or USB serial port at a baud rate (8N1, raw)
//   udp-listen:0.0.0.0:14540        wait for the autopilot's datagrams on this address; reply to
//                                   whoever sent the last valid one (PX4 SITL's onboard link
//                                   sends to 14540)
//   udp:192.168.1.20:14555[:14550]  send to this peer (from this local port, else any), and take
//                                   datagrams from that peer only

#include <cstdint>
#include <optional>
#include <string>

namespace alight::mavlink {

/// Baud rates a serial link may use: the telemetry radios' 57600 up to the 921600 of a flight
/// controller's TELEM port to a companion computer.
inline constexpr int kBaudRates[] = {57600, 115200, 230400, 460800, 500000, 576000, 921600};
bool valid_baud(int baud);

struct LinkAddress {
  enum class Kind { kSerial, kUdpListen, kUdpPeer };
  Kind kind = Kind::kSerial;
  std::string device;  ///< serial: the device path
  int baud = 0;        ///< serial
  std::string host;    ///< udp-listen: local address to bind; udp: the peer
  int port = 0;        ///< udp-listen: local port; udp: the peer's port
  int local_port = 0;  ///< udp: local port to bind (0: any)

  std::string text() const;
};

/// The address, or nullopt and *why (a sentence a user can act on).
std::optional<LinkAddress> parse_link_address(const std::string& text, std::string* why);

}  // namespace alight::mavlink
