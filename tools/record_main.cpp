// alight-record: records every message of an LCM bus into a standard LCM log (the format
// lcm-logger writes and lcm-logplayer, lcm-spy and scripts/lcmlog.py read), and keeps them on a
// loaded computer. Debian's lcm-logger 1.3.1 lost messages with both cores busy (an IMU sample,
// a barometer sample): its subscription keeps LCM's default queue of 30 messages, so while its
// thread waits for a core the newest are dropped, silently. Here:
//  - the receiving threads run at real-time priority (SCHED_RR) when the process may, else at
//    the lowest nice it may have, so a busy core gives them its time when a datagram arrives;
//  - the socket buffer is as large as the kernel allows (net.core.rmem_max; scripts/setup raises
//    it), LCM's queue is a million messages deep, and a writer thread of normal priority
//    empties a queue bounded in bytes into the file;
//  - whatever could not be kept is counted and said: the kernel's drops on the socket
//    (/proc/net/udp), messages refused for a full queue, write errors. Every 10 s and at the end
//    on stderr, and once a second on NODE_STATUS (node "alight-record": per channel the messages
//    recorded, and the pseudo-inputs record:socket and record:queue with their drops).
// Every message is recorded as it came, origin trailer and all (forensics needs the forgeries
// too); none is judged. Stops on SIGINT / SIGTERM after writing what it holds.
//   alight-record [--lcm-url URL] [-c REGEX] [--max-queue-mb N] FILE
#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <alight/node_status_t.hpp>
#include <atomic>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "common/bus_auth.hpp"
#include "common/channels.hpp"
#include "common/node.hpp"

namespace {

std::atomic<bool> g_stop{false};
extern "C" void record_on_signal(int) { g_stop = true; }

struct Event {
  int64_t utime;
  std::string channel;
  std::vector<uint8_t> data;
};

// Messages handed from LCM's thread to the writer, bounded in bytes.
class Queue {
 public:
  explicit Queue(size_t max_bytes) : max_bytes_(max_bytes) {}
  bool push(Event e) {
    std::lock_guard<std::mutex> lock(m_);
    if (bytes_ + e.data.size() > max_bytes_) return false;
    bytes_ += e.data.size();
    q_.push_back(std::move(e));
    cv_.notify_one();
    return true;
  }
  // Waits up to 100 ms for events; takes all there are.
  std::deque<Event> take() {
    std::unique_lock<std::mutex> lock(m_);
    cv_.wait_for(lock, std::chrono::milliseconds(100), [&] { return !q_.empty(); });
    std::deque<Event> out;
    out.swap(q_);
    bytes_ = 0;
    return out;
  }

 private:
  std::mutex m_;
  std::condition_variable cv_;
  std::deque<Event> q_;
  size_t bytes_ = 0;
  size_t max_bytes_;
};

struct Recorder {
  explicit Recorder(Queue* q) : queue(q) {}
  Queue* queue;
  std::mutex stats_mutex;
  std::map<std::string, int64_t> per_channel;
  uint64_t received = 0, refused = 0;
  void on(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const auto* p = static_cast<const uint8_t*>(rbuf->data);
    const bool kept =
        queue->push(Event{rbuf->recv_utime, channel, std::vector<uint8_t>(p, p + rbuf->data_size)});
    std::lock_guard<std::mutex> lock(stats_mutex);
    ++received;
    if (!kept) ++refused;
    // Bounded: a flood of invented channel names must not grow this map.
    if (per_channel.count(channel) || per_channel.size() < 256) ++per_channel[channel];
  }
};

// Gives the calling thread (and the threads it creates from now on: LCM's receive thread) the
// best scheduling the process may have. Returns what it got, for the log.
std::string raise_priority() {
  sched_param sp{};
  sp.sched_priority = 10;
  if (pthread_setschedparam(pthread_self(), SCHED_RR, &sp) == 0) return "real-time (SCHED_RR 10)";
  for (int nice = -10; nice < 0; ++nice)
    if (setpriority(PRIO_PROCESS, 0, nice) == 0) return "nice " + std::to_string(nice);
  return "normal (not permitted to raise it: run as root or with CAP_SYS_NICE)";
}

// The kernel's drop count of this process's UDP sockets bound to `port` (/proc/net/udp: the last
// column; the inode ties a socket to this process's descriptors).
uint64_t socket_drops(int port) {
  std::set<std::string> inodes;
  for (const auto& fd : std::filesystem::directory_iterator("/proc/self/fd")) {
    std::error_code ec;
    const auto target = std::filesystem::read_symlink(fd.path(), ec).string();
    if (!ec && target.rfind("socket:[", 0) == 0) inodes.insert(target.substr(8, target.size() - 9));
  }
  uint64_t drops = 0;
  std::ifstream f("/proc/net/udp");
  std::string line;
  std::getline(f, line);  // header
  char want[8];
  std::snprintf(want, sizeof want, ":%04X", port);
  while (std::getline(f, line)) {
    std::istringstream in(line);
    std::string sl, local, remote, st, queues, tr, retr, uid, timeout, inode, ref, ptr, drop;
    in >> sl >> local >> remote >> st >> queues >> tr >> retr >> uid >> timeout >> inode >> ref >>
        ptr >> drop;
    if (local.size() >= 5 && local.substr(local.size() - 5) == want && inodes.count(inode))
      drops += std::strtoull(drop.c_str(), nullptr, 10);
  }
  return drops;
}

int port_of(const std::string& url) {
  const size_t colon = url.find(':', url.find("//") + 2);
  if (colon == std::string::npos) return 7667;
  try {
    return std::stoi(url.substr(colon + 1));
  } catch (const std::exception&) {
    return 7667;
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"alight-record: every message of an LCM bus into an LCM log, kept under load"};
  std::string url, channels = ".*", path;
  double max_queue_mb = 512;
  app.add_option("-l,--lcm-url", url, "LCM URL (default: $LCM_DEFAULT_URL, else alight's)");
  app.add_option("-c,--channel", channels, "Channels to record (regular expression)");
  app.add_option("--max-queue-mb", max_queue_mb,
                 "Messages received but not yet written that may wait in memory [MB]")
      ->check(CLI::Range(1.0, 8192.0));
  app.add_option("file", path, "The log to write (must not exist)")->required();
  CLI11_PARSE(app, argc, argv);
  if (url.empty()) {
    const char* env = std::getenv("LCM_DEFAULT_URL");
    url = env && *env ? env : alight::kDefaultLcmUrl;
  }
  if (std::filesystem::exists(path)) {
    std::fprintf(stderr, "alight-record: %s exists; not overwriting a log\n", path.c_str());
    return 2;
  }
  struct sigaction sa {};
  sa.sa_handler = record_on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);

  // Before LCM starts its receive thread, which inherits the scheduling.
  const std::string priority = raise_priority();
  // As deep a socket buffer as the kernel allows (LCM asks for it; the kernel caps it).
  int rmem = 0;
  {
    std::ifstream f("/proc/sys/net/core/rmem_max");
    f >> rmem;
  }
  lcm::LCM lcm(alight::with_receive_buffer(url, std::max(rmem, alight::kDefaultRecvBufBytes)));
  if (!lcm.good()) {
    std::fprintf(stderr, "alight-record: cannot open LCM at %s\n", url.c_str());
    return 1;
  }
  lcm::LogFile log(path, "w");
  if (!log.good()) {
    std::fprintf(stderr, "alight-record: cannot write %s\n", path.c_str());
    return 2;
  }
  Queue queue(static_cast<size_t>(max_queue_mb * 1024 * 1024));
  Recorder rec(&queue);
  lcm::Subscription* sub = lcm.subscribe(channels, &Recorder::on, &rec);
  sub->setQueueCapacity(1'000'000);
  const int port = port_of(url);
  // Its NODE_STATUS signed like the nodes' when the bus is ($ALIGHT_BUS_KEY_FILE).
  std::optional<alight::bus::BusKey> key;
  if (const char* k = std::getenv("ALIGHT_BUS_KEY_FILE"); k && *k) {
    try {
      key = alight::bus::load_bus_key(k);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "alight-record: ALIGHT_BUS_KEY_FILE: %s\n", e.what());
      return 2;
    }
  }
  alight::bus::Sealer sealer(alight::bus::draw_source_id(), key);
  std::fprintf(stderr, "alight-record: %s -> %s, priority %s, socket buffer %d bytes\n",
               url.c_str(), path.c_str(), priority.c_str(), rmem);

  // The writer: normal priority (disk I/O), never in LCM's way.
  std::atomic<bool> writer_done{false};
  uint64_t written = 0, write_errors = 0;
  std::thread writer([&] {
    sched_param normal{};
    pthread_setschedparam(pthread_self(), SCHED_OTHER, &normal);
    int64_t next_flush = alight::steady_utime();
    for (;;) {
      auto events = queue.take();
      for (auto& e : events) {
        lcm::LogEvent ev{};
        ev.timestamp = e.utime;
        ev.channel = e.channel;
        ev.datalen = static_cast<int32_t>(e.data.size());
        ev.data = e.data.data();
        if (log.writeEvent(&ev) == 0)
          ++written;
        else
          ++write_errors;
      }
      if (alight::steady_utime() >= next_flush) {
        std::fflush(log.getFilePtr());
        next_flush = alight::steady_utime() + 100'000;
      }
      if (writer_done && events.empty()) break;
    }
    std::fflush(log.getFilePtr());
  });

  const auto report = [&](bool final) {
    uint64_t received, refused;
    std::map<std::string, int64_t> per_channel;
    {
      std::lock_guard<std::mutex> lock(rec.stats_mutex);
      received = rec.received;
      refused = rec.refused;
      per_channel = rec.per_channel;
    }
    const uint64_t drops = socket_drops(port);
    std::fprintf(stderr,
                 "alight-record: %s%llu received, %llu written, %llu refused for a full queue, "
                 "%llu dropped by the kernel (socket buffer full), %llu write errors\n",
                 final ? "end: " : "", static_cast<unsigned long long>(received),
                 static_cast<unsigned long long>(written), static_cast<unsigned long long>(refused),
                 static_cast<unsigned long long>(drops),
                 static_cast<unsigned long long>(write_errors));
    alight::node_status_t st{};
    st.utime = alight::wall_utime();
    st.node = "alight-record";
    st.pid = static_cast<int32_t>(getpid());
    for (const auto& [channel, n] : per_channel) {
      alight::channel_stats_t c{};
      c.channel = channel;
      c.received = n;
      st.channels.push_back(c);
    }
    alight::channel_stats_t s{};
    s.channel = "record:socket";
    s.dropped = static_cast<int64_t>(drops);
    st.channels.push_back(s);
    alight::channel_stats_t q{};
    q.channel = "record:queue";
    q.received = static_cast<int64_t>(received);
    q.dropped = static_cast<int64_t>(refused);
    q.rejected_values = static_cast<int64_t>(write_errors);
    st.channels.push_back(q);
    st.n = static_cast<int32_t>(st.channels.size());
    st.source = static_cast<int64_t>(sealer.source());
    st.signed_bus = sealer.signing();
    std::vector<uint8_t> bytes(static_cast<size_t>(st.getEncodedSize()));
    st.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    sealer.seal(bytes, alight::channels::kNodeStatus, st.utime);
    lcm.publish(alight::channels::kNodeStatus, bytes.data(), static_cast<unsigned>(bytes.size()));
  };
  int64_t next_status = alight::steady_utime() + 1'000'000;
  int64_t next_log = alight::steady_utime() + 10'000'000;
  while (!g_stop) {
    lcm.handleTimeout(100);
    const int64_t now = alight::steady_utime();
    if (now >= next_status) {
      report(now >= next_log);
      next_status = now + 1'000'000;
      if (now >= next_log) next_log = now + 10'000'000;
    }
  }
  // What arrived meanwhile, then the rest of the queue.
  while (lcm.handleTimeout(0) > 0) {
  }
  writer_done = true;
  writer.join();
  report(true);
  return 0;
}
