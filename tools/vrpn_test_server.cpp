#include "tools/vrpn_test_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>

namespace alight::tools {

namespace {

// Network order, written out byte by byte (the description: "32-bit integers sent in network
// order"; doubles as 64-bit IEEE 754 in the same order).
void be32(std::vector<uint8_t>& b, uint32_t v) {
  b.push_back(static_cast<uint8_t>(v >> 24));
  b.push_back(static_cast<uint8_t>(v >> 16));
  b.push_back(static_cast<uint8_t>(v >> 8));
  b.push_back(static_cast<uint8_t>(v));
}
void be64f(std::vector<uint8_t>& b, double d) {
  uint64_t v;
  std::memcpy(&v, &d, 8);
  be32(b, static_cast<uint32_t>(v >> 32));
  be32(b, static_cast<uint32_t>(v));
}
uint32_t read_be32(const uint8_t* p) {
  return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | p[3];
}

int64_t now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// A description: "length of name + 1", the name, its NUL (payload length 5 + strlen).
std::vector<uint8_t> description(const std::string& name) {
  std::vector<uint8_t> p;
  be32(p, static_cast<uint32_t>(name.size() + 1));
  for (char c : name) p.push_back(static_cast<uint8_t>(c));
  p.push_back(0);
  return p;
}

}  // namespace

VrpnTestServer::VrpnTestServer(VrpnServerOptions options) : options_(std::move(options)) {}

VrpnTestServer::~VrpnTestServer() { close(); }

bool VrpnTestServer::listen() {
  if (listener_ >= 0) return true;
  listener_ = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (listener_ < 0) return false;
  const int one = 1;
  setsockopt(listener_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<uint16_t>(port_ ? port_ : options_.port));
  socklen_t len = sizeof a;
  if (bind(listener_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
      ::listen(listener_, 4) != 0 ||
      getsockname(listener_, reinterpret_cast<sockaddr*>(&a), &len) != 0) {
    ::close(listener_);
    listener_ = -1;
    return false;
  }
  port_ = ntohs(a.sin_port);
  return true;
}

bool VrpnTestServer::accept(double timeout_s, const std::vector<std::string>& objects) {
  if (listener_ < 0) return false;
  drop_client();
  pollfd p{listener_, POLLIN, 0};
  if (poll(&p, 1, static_cast<int>(timeout_s * 1000)) <= 0) return false;
  client_ = ::accept4(listener_, nullptr, nullptr, SOCK_CLOEXEC);
  if (client_ < 0) return false;
  const int one = 1;
  setsockopt(client_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);

  // Cookie: "vrpn: ver. " MM.mm, two spaces, log mode '0', NUL padding to 24 bytes.
  std::vector<uint8_t> cookie(24, 0);
  const std::string text = "vrpn: ver. " + options_.version + "  0";
  std::memcpy(cookie.data(), text.data(), std::min<size_t>(text.size(), 24));
  if (!write_all(cookie.data(), cookie.size())) return false;
  client_cookie_.assign(24, 0);
  client_bytes_.clear();
  if (!read_exact(client_cookie_.data(), 24, timeout_s) ||
      std::memcmp(client_cookie_.data(), "vrpn: ver. 07.", 14) != 0) {
    drop_client();
    return false;
  }

  senders_.clear();
  types_.clear();
  std::vector<uint8_t> out;
  const int64_t t = now_us();
  int32_t sender = options_.first_sender_id;
  for (const std::string& name : std::vector<std::string>{"VRPN Control"})
    senders_[name] = sender++;
  for (const auto& o : objects) senders_[o] = sender++;
  int32_t type = options_.first_type_id;
  for (const char* name :
       {"VRPN_Connection_Got_First_Connection", "VRPN_Connection_Got_Connection",
        "vrpn_Tracker Pos_Quat", "vrpn_Tracker Velocity", "vrpn_Tracker Acceleration",
        "vrpn_Tracker To_Room", "vrpn_Tracker Workspace"})
    types_[name] = type++;
  for (const auto& [name, id] : senders_) {
    const auto b = frame(-1, id, t, description(name));
    out.insert(out.end(), b.begin(), b.end());
  }
  for (const auto& [name, id] : types_) {
    const auto b = frame(-2, id, t, description(name));
    out.insert(out.end(), b.begin(), b.end());
  }
  return write_all(out.data(), out.size());
}

std::vector<std::string> VrpnTestServer::client_descriptions(double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  std::vector<std::string> names;
  while (client_ >= 0) {
    names.clear();
    // Parses what arrived: 24-byte header (length = 24 + payload), payload padded to 8.
    size_t at = 0;
    while (client_bytes_.size() - at >= 24) {
      const uint32_t length = read_be32(&client_bytes_[at]);
      const auto type = static_cast<int32_t>(read_be32(&client_bytes_[at + 16]));
      if (length < 24) return names;
      const size_t payload = length - 24, padded = (payload + 7) / 8 * 8;
      if (client_bytes_.size() - at < 24 + padded) break;
      if ((type == -1 || type == -2) && payload >= 5) {
        const uint32_t n = read_be32(&client_bytes_[at + 24]);
        if (n >= 1 && 4 + n <= payload)
          names.emplace_back(reinterpret_cast<const char*>(&client_bytes_[at + 28]), n - 1);
      }
      at += 24 + padded;
    }
    const auto left = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    pollfd p{client_, POLLIN, 0};
    if (poll(&p, 1, std::max(1, static_cast<int>(left.count() * 1000))) <= 0) break;
    uint8_t buf[4096];
    const ssize_t n = recv(client_, buf, sizeof buf, 0);
    if (n <= 0) break;
    client_bytes_.insert(client_bytes_.end(), buf, buf + n);
  }
  return names;
}

std::vector<uint8_t> VrpnTestServer::frame(int32_t type, int32_t sender, int64_t stamp_us,
                                           const std::vector<uint8_t>& payload) {
  std::vector<uint8_t> b;
  be32(b, static_cast<uint32_t>(24 + payload.size()));
  be32(b, static_cast<uint32_t>(stamp_us / 1000000));
  be32(b, static_cast<uint32_t>(stamp_us % 1000000));
  be32(b, static_cast<uint32_t>(sender));
  be32(b, static_cast<uint32_t>(type));
  be32(b, 0);  // sequence number: the sixth header word, for sniffers
  b.insert(b.end(), payload.begin(), payload.end());
  while (b.size() % 8) b.push_back(0);
  return b;
}

std::vector<uint8_t> VrpnTestServer::pose_payload(const ServedPose& pose) {
  std::vector<uint8_t> p;
  be32(p, static_cast<uint32_t>(pose.sensor));
  be32(p, static_cast<uint32_t>(pose.sensor));  // alignment filler
  for (double v : pose.pos) be64f(p, v);
  for (double v : pose.quat_xyzw) be64f(p, v);
  return p;
}

int32_t VrpnTestServer::sender_id(const std::string& object) const {
  const auto it = senders_.find(object);
  return it == senders_.end() ? -100 : it->second;
}

int32_t VrpnTestServer::type_id(const std::string& name) const {
  const auto it = types_.find(name);
  return it == types_.end() ? -100 : it->second;
}

bool VrpnTestServer::send_pose(const ServedPose& pose) {
  const auto b = frame(type_id("vrpn_Tracker Pos_Quat"), sender_id(pose.object), pose.stamp_us,
                       pose_payload(pose));
  return write_all(b.data(), b.size());
}

bool VrpnTestServer::send_velocity(const std::string& object, int32_t sensor, int64_t stamp_us,
                                   const double vel[3]) {
  std::vector<uint8_t> p;
  be32(p, static_cast<uint32_t>(sensor));
  be32(p, static_cast<uint32_t>(sensor));
  for (int i = 0; i < 3; ++i) be64f(p, vel[i]);
  for (double q : {0.0, 0.0, 0.0, 1.0}) be64f(p, q);
  be64f(p, 0.0);  // vel_quat_dt
  const auto b = frame(type_id("vrpn_Tracker Velocity"), sender_id(object), stamp_us, p);
  return write_all(b.data(), b.size());
}

bool VrpnTestServer::send_raw(const std::vector<uint8_t>& bytes) {
  return write_all(bytes.data(), bytes.size());
}

void VrpnTestServer::drop_client() {
  if (client_ >= 0) ::close(client_);
  client_ = -1;
}

void VrpnTestServer::close() {
  drop_client();
  if (listener_ >= 0) ::close(listener_);
  listener_ = -1;
}

bool VrpnTestServer::write_all(const uint8_t* data, size_t size) {
  if (client_ < 0) return false;
  size_t done = 0;
  while (done < size) {
    const ssize_t n = send(client_, data + done, size - done, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      drop_client();
      return false;
    }
    done += static_cast<size_t>(n);
  }
  bytes_sent_ += size;
  return true;
}

bool VrpnTestServer::read_exact(uint8_t* data, size_t size, double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  size_t done = 0;
  while (done < size) {
    const auto left = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now());
    pollfd p{client_, POLLIN, 0};
    if (left.count() <= 0 || poll(&p, 1, std::max(1, static_cast<int>(left.count() * 1000))) <= 0)
      return false;
    const ssize_t n = recv(client_, data + done, size - done, 0);
    if (n <= 0) return false;
    done += static_cast<size_t>(n);
  }
  return true;
}

}  // namespace alight::tools
