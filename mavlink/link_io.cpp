#include "mavlink/link_io.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace alight::mavlink {

namespace {

speed_t speed_of(int baud) {
  switch (baud) {
    case 57600:
      return B57600;
    case 115200:
      return B115200;
    case 230400:
      return B230400;
    case 460800:
      return B460800;
    case 500000:
      return B500000;
    case 576000:
      return B576000;
    case 921600:
      return B921600;
    default:
      return B0;
  }
}

std::optional<sockaddr_in> resolve(const std::string& host, int port, std::string* error) {
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* found = nullptr;
  const int rc = getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found);
  if (rc != 0 || !found) {
    *error = "cannot resolve " + host + ": " + gai_strerror(rc);
    return std::nullopt;
  }
  sockaddr_in a{};
  std::memcpy(&a, found->ai_addr, sizeof a);
  freeaddrinfo(found);
  return a;
}

bool same_address(const sockaddr_in& a, const sockaddr_in& b) {
  return a.sin_addr.s_addr == b.sin_addr.s_addr && a.sin_port == b.sin_port;
}

}  // namespace

bool LinkIo::open(std::string* error) {
  close();
  return address_.kind == LinkAddress::Kind::kSerial ? open_serial(error) : open_udp(error);
}

void LinkIo::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (address_.kind == LinkAddress::Kind::kUdpListen) peer_.reset();
}

bool LinkIo::open_serial(std::string* error) {
  const speed_t speed = speed_of(address_.baud);
  if (speed == B0) {
    *error = address_.device + ": baud " + std::to_string(address_.baud) + " not supported";
    return false;
  }
  fd_ = ::open(address_.device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    *error = address_.device + ": " + std::strerror(errno) +
             (errno == EACCES ? " (add the user to the dialout group)" : "");
    return false;
  }
  // One process per port: a second reader would steal half of the bytes.
  if (ioctl(fd_, TIOCEXCL) != 0 && errno != ENOTTY) {
    *error = address_.device + ": cannot get exclusive access: " + std::strerror(errno);
    close();
    return false;
  }
  termios t{};
  if (tcgetattr(fd_, &t) != 0) {
    *error = address_.device + ": not a serial port: " + std::strerror(errno);
    close();
    return false;
  }
  cfmakeraw(&t);  // no echo, no canonical mode, no CR/LF translation, 8 bits
  t.c_cflag &= ~(PARENB | CSTOPB | CSIZE | CRTSCTS);
  t.c_cflag |= CS8 | CLOCAL | CREAD;
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  if (cfsetispeed(&t, speed) != 0 || cfsetospeed(&t, speed) != 0 ||
      tcsetattr(fd_, TCSANOW, &t) != 0) {
    *error = address_.device + ": cannot set " + std::to_string(address_.baud) +
             " baud raw mode: " + std::strerror(errno);
    close();
    return false;
  }
  tcflush(fd_, TCIOFLUSH);  // what the port held before we opened it is not ours
  return true;
}

bool LinkIo::open_udp(std::string* error) {
  fd_ = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) {
    *error = std::string("socket: ") + std::strerror(errno);
    return false;
  }
  const int one = 1;
  setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  // The kernel's arrival time of each datagram (last_receipt_wall_us()): a reader busy
  // elsewhere for milliseconds would otherwise stamp a queue of them all at once.
  setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMP, &one, sizeof one);
  sockaddr_in local{};
  local.sin_family = AF_INET;
  if (address_.kind == LinkAddress::Kind::kUdpListen) {
    const auto a = resolve(address_.host, address_.port, error);
    if (!a) {
      close();
      return false;
    }
    local = *a;
  } else {
    const auto a = resolve(address_.host, address_.port, error);
    if (!a) {
      close();
      return false;
    }
    peer_ = *a;
    local.sin_addr.s_addr = htonl(INADDR_ANY);
    local.sin_port = htons(static_cast<uint16_t>(address_.local_port));
  }
  if (bind(fd_, reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0) {
    *error = "bind " + address_.text() + ": " + std::strerror(errno);
    close();
    return false;
  }
  return true;
}

long LinkIo::read(std::span<uint8_t> out, std::string* error) {
  if (fd_ < 0) return -1;
  for (;;) {
    ssize_t n;
    if (address_.kind == LinkAddress::Kind::kSerial) {
      n = ::read(fd_, out.data(), out.size());
      if (n == 0) {
        // VMIN = 0: nothing now, or the device is gone: a tty that was hung up (USB adapter
        // unplugged, pty master closed) reads 0 bytes forever instead of failing, and polls
        // readable, so the node would spin without ever reopening it.
        pollfd p{fd_, POLLIN, 0};
        if (poll(&p, 1, 0) > 0 && (p.revents & (POLLHUP | POLLERR | POLLNVAL))) {
          *error = address_.text() + ": read: the device hung up (unplugged or closed)";
          return -1;
        }
        return 0;
      }
    } else {
      sockaddr_in from{};
      iovec iov{out.data(), out.size()};
      alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timeval))];
      msghdr msg{};
      msg.msg_name = &from;
      msg.msg_namelen = sizeof from;
      msg.msg_iov = &iov;
      msg.msg_iovlen = 1;
      msg.msg_control = control;
      msg.msg_controllen = sizeof control;
      n = recvmsg(fd_, &msg, 0);
      if (n >= 0) {
        last_receipt_wall_us_ = 0;
        for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c)) {
          if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMP) {
            timeval tv;
            std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
            last_receipt_wall_us_ = int64_t{tv.tv_sec} * 1'000'000 + tv.tv_usec;
          }
        }
        if (address_.kind == LinkAddress::Kind::kUdpPeer) {
          if (!same_address(from, *peer_)) {
            ++stats_.datagrams_foreign;
            continue;
          }
        } else {
          peer_ = from;  // reply to whoever talks to us (PX4 SITL picks its own port)
        }
      }
    }
    if (n > 0) {
      stats_.bytes_read += static_cast<uint64_t>(n);
      return n;
    }
    if (n == 0) return 0;
    if (errno == EINTR) continue;
    if (errno == EAGAIN || errno == EWOULDBLOCK) return 0;
    // A UDP peer that is not (yet) listening reports ECONNREFUSED on a later call: not fatal.
    if (errno == ECONNREFUSED) return 0;
    *error = address_.text() + ": read: " + std::strerror(errno);
    return -1;
  }
}

long LinkIo::write(std::span<const uint8_t> bytes, std::string* error) {
  if (fd_ < 0) return -1;
  if (bytes.empty()) return 0;
  ssize_t n;
  if (address_.kind == LinkAddress::Kind::kSerial) {
    n = ::write(fd_, bytes.data(), bytes.size());
  } else {
    if (!peer_) {
      stats_.bytes_unsent += bytes.size();
      return 0;
    }
    n = sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&*peer_),
               sizeof *peer_);
  }
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR || errno == ECONNREFUSED ||
        errno == ENOBUFS) {
      stats_.bytes_unsent += bytes.size();
      return 0;
    }
    *error = address_.text() + ": write: " + std::strerror(errno);
    return -1;
  }
  stats_.bytes_written += static_cast<uint64_t>(n);
  stats_.bytes_unsent += bytes.size() - static_cast<size_t>(n);
  return n;
}

}  // namespace alight::mavlink
