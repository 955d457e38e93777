#pragma once
// cpp-httplib's server behind a gate that no slow client can hold (24 clients sending
// one header line every 0.8 s kept POST /api/command unanswered for 15 s, because httplib gives
// every accepted connection a worker thread at once, and a worker waits as long as bytes keep
// trickling in).
//
// Here one gate thread polls every connection whose request head is still arriving: it reads
// what arrived without blocking, checks the head against size and header-count limits and a
// deadline from the first byte (408 / 431 and close otherwise), and only then hands the
// connection, with the bytes read, to a worker. Command requests (POST /api/command) go to their
// own workers, and only once their body has arrived too, so a KILL never waits behind page
// traffic and a worker never waits for a command's bytes. Workers read and write through a
// stream with a per-request deadline on the steady clock and a per-wait timeout; a kept-alive
// connection goes back to the gate between requests. The pattern is nginx's and lighttpd's
// (event loop for the head, bounded workers for the handler), built on httplib's own request
// parsing and routing (Server::process_request).

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "ground_station/http.hpp"

namespace alight::ground_station {

struct HttpLimits {
  int workers = 32;                  ///< general workers (page, state, video frames)
  int command_workers = 2;           ///< workers for POST /api/command only
  size_t max_queued = 64;            ///< complete requests waiting for a worker, per pool
  size_t max_pending_heads = 256;    ///< connections whose head is arriving; oldest closed beyond
  double io_timeout_s = 2.0;         ///< longest wait for one read or write [s]
  double head_deadline_s = 2.0;      ///< head (and a command's body) complete within this [s]
  double request_deadline_s = 10.0;  ///< a whole request, from its head to its answer [s]
  double idle_timeout_s = 2.0;       ///< a kept-alive connection idle longer is closed [s]
  size_t max_header_count = 64;
  size_t max_head_bytes = 16384;
  size_t max_payload_bytes = 65536;
  int keep_alive_max = 100;  ///< requests per connection
};

struct HttpGateCounters {
  uint64_t heads_timed_out = 0;   ///< 408: head not complete within its deadline
  uint64_t heads_too_large = 0;   ///< 431: head over max_head_bytes or max_header_count
  uint64_t pending_dropped = 0;   ///< oldest pending head closed (max_pending_heads)
  uint64_t queue_full = 0;        ///< 503: no worker and the pool's queue full
  uint64_t command_requests = 0;  ///< requests routed to the command workers
};

class HardenedServer : public httplib::Server {
 public:
  explicit HardenedServer(HttpLimits limits);
  ~HardenedServer() override;
  HardenedServer(const HardenedServer&) = delete;
  HardenedServer& operator=(const HardenedServer&) = delete;

  /// After bind_to_port: httplib listens with a backlog of 5, so a burst of connections (a page
  /// opening, or slow clients) loses SYNs, each costing the client a 1 s retransmission.
  void widen_backlog(int backlog);
  /// After httplib's stop() returned and its listen thread was joined: closes every pending and
  /// active connection and joins the gate and the workers.
  void shutdown_all();
  HttpGateCounters gate_counters() const;

 private:
  struct Conn {
    int fd = -1;
    std::string buffered;  ///< bytes already read: the head, maybe body and more
    int served = 0;        ///< requests answered on this connection
  };
  class Pool;
  struct Pending;

  // Called by httplib's accept loop (through an inline task queue) for every new connection.
  bool process_and_close_socket(socket_t sock) override;
  void gate_add(Conn conn);
  void gate_loop();
  bool gate_on_bytes(Pending& p, const char* data, size_t n, int64_t now_us);
  void dispatch(Pending& p);
  void serve(Conn conn);
  void close_conn(int fd, const char* answer);

  HttpLimits limits_;
  std::atomic<bool> stopping_{false};

  std::mutex inbox_mutex_;
  std::vector<Conn> inbox_;
  int wake_[2] = {-1, -1};
  std::thread gate_;

  std::unique_ptr<Pool> general_;
  std::unique_ptr<Pool> commands_;

  std::mutex active_mutex_;
  std::set<int> active_fds_;

  std::atomic<uint64_t> heads_timed_out_{0}, heads_too_large_{0}, pending_dropped_{0},
      queue_full_{0}, command_requests_{0};
};

}  // namespace alight::ground_station
