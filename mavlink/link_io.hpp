#pragma once
// The byte pipe to the autopilot for alight-mavlink and alight-sim's simulated autopilot: a
// serial port in raw mode (termios: 8N1, no flow control, no echo, no line discipline, the baud
// rate validated) or a UDP socket. Non-blocking: read() returns what has arrived, write() what
// the device takes now; bytes it cannot take are counted and dropped rather than queued behind a
// slow link (a setpoint queued for seconds is worse than one lost). Not pure: node-side only.

#include <netinet/in.h>

#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "mavlink/link_address.hpp"

namespace alight::mavlink {

struct LinkIoStats {
  uint64_t bytes_read = 0;
  uint64_t bytes_written = 0;
  uint64_t bytes_unsent = 0;       ///< the device could not take them (or no UDP peer yet)
  uint64_t datagrams_foreign = 0;  ///< udp: from another address than the peer, ignored
};

class LinkIo {
 public:
  explicit LinkIo(LinkAddress address) : address_(std::move(address)) {}
  ~LinkIo() { close(); }
  LinkIo(const LinkIo&) = delete;
  LinkIo& operator=(const LinkIo&) = delete;

  /// Opens the device or socket; false and *error (naming the device and the reason) on failure.
  bool open(std::string* error);
  void close();
  bool is_open() const { return fd_ >= 0; }
  int fd() const { return fd_; }

  /// Reads what has arrived (at most out.size() bytes; one datagram for UDP). 0: nothing now;
  /// -1: the device failed (unplugged, closed): close and reopen it; *error says why.
  long read(std::span<uint8_t> out, std::string* error);
  /// Writes as much as the device takes now; -1 when it failed.
  long write(std::span<const uint8_t> bytes, std::string* error);

  const LinkAddress& address() const { return address_; }
  const LinkIoStats& stats() const { return stats_; }
  /// udp-listen: whether a peer has been heard (replies go to it).
  bool has_peer() const { return peer_.has_value(); }
  /// udp: when the kernel received the datagram the last read() returned (Unix time [us]; 0
  /// for a serial port or when the kernel gave no time).
  int64_t last_receipt_wall_us() const { return last_receipt_wall_us_; }

 private:
  bool open_serial(std::string* error);
  bool open_udp(std::string* error);

  LinkAddress address_;
  int fd_ = -1;
  std::optional<sockaddr_in> peer_;  // udp: where datagrams go
  int64_t last_receipt_wall_us_ = 0;
  LinkIoStats stats_;
};

}  // namespace alight::mavlink
