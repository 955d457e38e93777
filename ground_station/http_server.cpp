#include "ground_station/http_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>

#include "ground_station/http_head.hpp"

namespace alight::ground_station {

namespace {

int64_t now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}
int64_t to_us(double s) { return static_cast<int64_t>(s * 1e6); }

constexpr const char* k408 =
    "HTTP/1.1 408 Request Timeout\r\nConnection: close\r\nContent-Length: 0\r\n\r\n";
constexpr const char* k431 =
    "HTTP/1.1 431 Request Header Fields Too Large\r\nConnection: close\r\nContent-Length: "
    "0\r\n\r\n";
constexpr const char* k503 =
    "HTTP/1.1 503 Service Unavailable\r\nConnection: close\r\nRetry-After: 1\r\nContent-Length: "
    "0\r\n\r\n";

// httplib's accept loop hands each connection to a task queue; this one runs the task at once
// in the accept thread, where process_and_close_socket only passes the socket to the gate.
class InlineQueue : public httplib::TaskQueue {
 public:
  void enqueue(std::function<void()> fn) override { fn(); }
  void shutdown() override {}
};

void ip_and_port(const sockaddr_storage& addr, std::string& ip, int& port) {
  char host[NI_MAXHOST] = {0};
  const socklen_t len = addr.ss_family == AF_INET6 ? sizeof(sockaddr_in6) : sizeof(sockaddr_in);
  if (getnameinfo(reinterpret_cast<const sockaddr*>(&addr), len, host, sizeof host, nullptr, 0,
                  NI_NUMERICHOST) == 0)
    ip = host;
  if (addr.ss_family == AF_INET)
    port = ntohs(reinterpret_cast<const sockaddr_in*>(&addr)->sin_port);
  else if (addr.ss_family == AF_INET6)
    port = ntohs(reinterpret_cast<const sockaddr_in6*>(&addr)->sin6_port);
}

// A connection as httplib's request parser reads it: first the bytes the gate already read, then
// the socket, every wait bounded by the I/O timeout and the request's deadline.
class DeadlineStream : public httplib::Stream {
 public:
  DeadlineStream(int fd, std::string prefix, int64_t io_timeout_us, int64_t deadline_us)
      : fd_(fd),
        buf_(std::move(prefix)),
        io_timeout_us_(io_timeout_us),
        deadline_us_(deadline_us) {}

  bool is_readable() const override { return pos_ < buf_.size() || wait(POLLIN); }
  bool is_writable() const override { return wait(POLLOUT); }

  ssize_t read(char* ptr, size_t size) override {
    if (pos_ >= buf_.size()) {
      buf_.clear();
      pos_ = 0;
      char tmp[4096];
      ssize_t n = -1;
      do {
        if (!wait(POLLIN)) return -1;
        n = ::recv(fd_, tmp, sizeof tmp, MSG_DONTWAIT);
      } while (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR));
      if (n <= 0) return n == 0 ? 0 : -1;
      buf_.assign(tmp, static_cast<size_t>(n));
    }
    const size_t k = std::min(size, buf_.size() - pos_);
    std::memcpy(ptr, buf_.data() + pos_, k);
    pos_ += k;
    return static_cast<ssize_t>(k);
  }

  ssize_t write(const char* ptr, size_t size) override {
    for (;;) {
      if (!wait(POLLOUT)) return -1;
      const ssize_t n = ::send(fd_, ptr, size, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n >= 0 || (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) return n;
    }
  }

  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    sockaddr_storage addr{};
    socklen_t len = sizeof addr;
    if (getpeername(fd_, reinterpret_cast<sockaddr*>(&addr), &len) == 0)
      ip_and_port(addr, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    sockaddr_storage addr{};
    socklen_t len = sizeof addr;
    if (getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len) == 0)
      ip_and_port(addr, ip, port);
  }
  socket_t socket() const override { return fd_; }

  std::string leftover() const { return buf_.substr(std::min(pos_, buf_.size())); }

 private:
  bool wait(short events) const {
    for (;;) {
      const int64_t left_us = std::min(io_timeout_us_, deadline_us_ - now_us());
      if (left_us <= 0) return false;
      pollfd p{fd_, events, 0};
      const int r = ::poll(&p, 1, static_cast<int>((left_us + 999) / 1000));
      if (r > 0) return (p.revents & (events | POLLHUP | POLLERR)) != 0;
      if (r == 0) return false;
      if (errno != EINTR) return false;
    }
  }

  int fd_;
  std::string buf_;
  size_t pos_ = 0;
  int64_t io_timeout_us_;
  int64_t deadline_us_;
};

}  // namespace

// Fixed worker threads over a bounded queue of connections whose request has arrived.
class HardenedServer::Pool {
 public:
  Pool(HardenedServer* server, int n_threads, size_t max_queued)
      : server_(server), max_queued_(max_queued) {
    for (int i = 0; i < n_threads; ++i) threads_.emplace_back([this] { work(); });
  }
  ~Pool() { shutdown(); }
  bool try_push(Conn conn) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_ || queue_.size() >= max_queued_) return false;
    queue_.push_back(std::move(conn));
    cv_.notify_one();
    return true;
  }
  void shutdown() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    cv_.notify_all();
    for (auto& t : threads_)
      if (t.joinable()) t.join();
    threads_.clear();
    for (auto& c : queue_) ::close(c.fd);
    queue_.clear();
  }

 private:
  void work() {
    for (;;) {
      Conn conn;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        cv_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
        if (stopping_) return;
        conn = std::move(queue_.front());
        queue_.pop_front();
      }
      server_->serve(std::move(conn));
    }
  }
  HardenedServer* server_;
  size_t max_queued_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Conn> queue_;
  std::vector<std::thread> threads_;
  bool stopping_ = false;
};

struct HardenedServer::Pending {
  Conn conn;
  HeadReader head;
  bool idle = false;  // kept-alive connection waiting for its next request's first byte
  bool command = false;
  size_t need = 0;  // bytes needed before dispatch (0: head not complete yet)
  int64_t deadline_us = 0;
  Pending(Conn c, size_t max_bytes, size_t max_headers)
      : conn(std::move(c)), head(max_bytes, max_headers) {}
};

HardenedServer::HardenedServer(HttpLimits limits) : limits_(limits) {
  if (::pipe2(wake_, O_CLOEXEC | O_NONBLOCK) != 0)
    throw std::runtime_error(std::string("ground station: pipe2 failed: ") + std::strerror(errno));
  new_task_queue = [] { return new InlineQueue; };
  set_payload_max_length(limits_.max_payload_bytes);
  general_ = std::make_unique<Pool>(this, limits_.workers, limits_.max_queued);
  commands_ = std::make_unique<Pool>(this, limits_.command_workers, limits_.max_queued);
  gate_ = std::thread([this] { gate_loop(); });
}

HardenedServer::~HardenedServer() {
  shutdown_all();
  ::close(wake_[0]);
  ::close(wake_[1]);
}

void HardenedServer::shutdown_all() {
  if (stopping_.exchange(true)) return;
  (void)!::write(wake_[1], "x", 1);
  if (gate_.joinable()) gate_.join();
  {
    // Workers blocked on a client wake up at once.
    std::lock_guard<std::mutex> lock(active_mutex_);
    for (int fd : active_fds_) ::shutdown(fd, SHUT_RDWR);
  }
  general_->shutdown();
  commands_->shutdown();
  std::lock_guard<std::mutex> lock(inbox_mutex_);
  for (auto& c : inbox_) ::close(c.fd);
  inbox_.clear();
}

HttpGateCounters HardenedServer::gate_counters() const {
  return {heads_timed_out_, heads_too_large_, pending_dropped_, queue_full_, command_requests_};
}

void HardenedServer::widen_backlog(int backlog) {
  const socket_t sock = svr_sock_;
  if (sock != INVALID_SOCKET && ::listen(sock, backlog) != 0)
    throw std::runtime_error(std::string("ground station: listen failed: ") + std::strerror(errno));
}

bool HardenedServer::process_and_close_socket(socket_t sock) {
  gate_add(Conn{sock, {}, 0});
  return true;
}

void HardenedServer::gate_add(Conn conn) {
  {
    std::lock_guard<std::mutex> lock(inbox_mutex_);
    if (stopping_) {
      ::close(conn.fd);
      return;
    }
    inbox_.push_back(std::move(conn));
  }
  (void)!::write(wake_[1], "x", 1);
}

void HardenedServer::close_conn(int fd, const char* answer) {
  if (answer) (void)!::send(fd, answer, std::strlen(answer), MSG_NOSIGNAL | MSG_DONTWAIT);
  ::shutdown(fd, SHUT_RDWR);
  ::close(fd);
}

void HardenedServer::gate_loop() {
  std::deque<std::unique_ptr<Pending>> pending;  // oldest first
  std::vector<pollfd> fds;
  while (!stopping_) {
    const int64_t t_in = now_us();
    {
      std::lock_guard<std::mutex> lock(inbox_mutex_);
      for (auto& c : inbox_) {
        auto p = std::make_unique<Pending>(std::move(c), limits_.max_head_bytes,
                                           limits_.max_header_count);
        if (p->conn.served > 0 && p->conn.buffered.empty()) {
          p->idle = true;
          p->deadline_us = t_in + to_us(limits_.idle_timeout_s);
        } else {
          p->deadline_us = t_in + to_us(limits_.head_deadline_s);
        }
        std::string first;
        first.swap(p->conn.buffered);
        if (!first.empty() && !gate_on_bytes(*p, first.data(), first.size(), t_in)) continue;
        pending.push_back(std::move(p));
      }
      inbox_.clear();
    }
    while (pending.size() > limits_.max_pending_heads) {
      ++pending_dropped_;
      close_conn(pending.front()->conn.fd, k503);
      pending.pop_front();
    }

    int64_t next_deadline = t_in + 100'000;
    fds.assign(1, pollfd{wake_[0], POLLIN, 0});
    for (const auto& p : pending) {
      fds.push_back(pollfd{p->conn.fd, POLLIN, 0});
      next_deadline = std::min(next_deadline, p->deadline_us);
    }
    const int timeout_ms =
        static_cast<int>(std::clamp<int64_t>((next_deadline - now_us() + 999) / 1000, 0, 100));
    const int r = ::poll(fds.data(), fds.size(), timeout_ms);
    if (r < 0 && errno != EINTR) break;
    if (fds[0].revents & POLLIN) {
      char drain[64];
      while (::read(wake_[0], drain, sizeof drain) > 0) {
      }
    }
    const int64_t t = now_us();
    std::deque<std::unique_ptr<Pending>> keep;
    for (size_t i = 0; i < pending.size(); ++i) {
      Pending& p = *pending[i];
      bool alive = true;
      if (r > 0 && (fds[i + 1].revents & (POLLIN | POLLHUP | POLLERR))) {
        char buf[4096];
        const ssize_t n = ::recv(p.conn.fd, buf, sizeof buf, MSG_DONTWAIT);
        if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
          close_conn(p.conn.fd, nullptr);
          alive = false;
        } else if (n > 0) {
          alive = gate_on_bytes(p, buf, static_cast<size_t>(n), t);
        }
      }
      if (alive && t >= p.deadline_us) {
        if (!p.idle) ++heads_timed_out_;
        close_conn(p.conn.fd, p.idle ? nullptr : k408);
        alive = false;
      }
      if (alive) keep.push_back(std::move(pending[i]));
    }
    pending.swap(keep);
  }
  for (auto& p : pending) close_conn(p->conn.fd, nullptr);
}

// Returns false when the connection left the gate (dispatched to a worker or closed).
bool HardenedServer::gate_on_bytes(Pending& p, const char* data, size_t n, int64_t t) {
  if (p.idle) {
    p.idle = false;
    p.deadline_us = t + to_us(limits_.head_deadline_s);
  }
  p.conn.buffered.append(data, n);
  if (p.need == 0) {
    p.head.feed(data, n);
    switch (p.head.state()) {
      case HeadReader::State::kMore:
        return true;
      case HeadReader::State::kTooLarge:
      case HeadReader::State::kTooManyHeaders:
        ++heads_too_large_;
        close_conn(p.conn.fd, k431);
        return false;
      case HeadReader::State::kComplete:
        break;
    }
    p.need = p.head.head().size();
    p.command = is_command_request_line(p.head.request_line());
    if (p.command) {
      // A command reaches its worker only with its whole body: a worker never waits for a
      // command's bytes. A body too large or of unknown length is for httplib to refuse.
      const auto length = p.head.content_length();
      if (length && *length <= limits_.max_payload_bytes) p.need += *length;
    }
  }
  if (p.conn.buffered.size() < p.need) {
    if (p.conn.buffered.size() > limits_.max_head_bytes + limits_.max_payload_bytes) {
      ++heads_too_large_;
      close_conn(p.conn.fd, k431);
      return false;
    }
    return true;
  }
  dispatch(p);
  return false;
}

void HardenedServer::dispatch(Pending& p) {
  const int fd = p.conn.fd;
  Pool& pool = p.command ? *commands_ : *general_;
  if (p.command) ++command_requests_;
  if (!pool.try_push(std::move(p.conn))) {
    ++queue_full_;
    close_conn(fd, k503);
  }
}

void HardenedServer::serve(Conn conn) {
  {
    std::lock_guard<std::mutex> lock(active_mutex_);
    active_fds_.insert(conn.fd);
  }
  DeadlineStream stream(conn.fd, std::move(conn.buffered), to_us(limits_.io_timeout_s),
                        now_us() + to_us(limits_.request_deadline_s));
  const bool close_after = conn.served + 1 >= limits_.keep_alive_max || stopping_;
  bool connection_closed = false;
  const bool ok = process_request(stream, close_after, connection_closed, nullptr);
  {
    std::lock_guard<std::mutex> lock(active_mutex_);
    active_fds_.erase(conn.fd);
  }
  if (!ok || close_after || connection_closed || stopping_) {
    close_conn(conn.fd, nullptr);
    return;
  }
  // Kept alive: back to the gate until the next request has arrived.
  conn.buffered = stream.leftover();
  ++conn.served;
  gate_add(std::move(conn));
}

}  // namespace alight::ground_station
