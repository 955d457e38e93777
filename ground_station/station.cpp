#include "ground_station/station.hpp"

#include <openssl/rand.h>
#include <spdlog/spdlog.h>

#include <alight/autonomy_status_t.hpp>
#include <alight/image_t.hpp>
#include <alight/node_status_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/process_status_t.hpp>
#include <alight/target_t.hpp>
#include <filesystem>

#include "ground_station/http.hpp"
#include "ground_station/http_server.hpp"
#include "ground_station/json_writer.hpp"

namespace alight::ground_station {

namespace {
constexpr size_t kMaxPendingCommands = 16;
constexpr int64_t kStateCacheUs = 50'000;  // clients polling together share one document

std::multimap<std::string, std::string> plain_headers(const httplib::Request& req) {
  return {req.headers.begin(), req.headers.end()};
}

void json_reply(httplib::Response& res, int status, const std::string& body) {
  res.status = status;
  res.set_header("Cache-Control", "no-store");
  res.set_content(body, "application/json");
}

std::string error_json(const std::string& message) {
  JsonWriter w;
  w.begin_object().field("ok", false).field("error", message).end_object();
  return w.str();
}
}  // namespace

std::string make_session_token() {
  uint8_t bytes[16];
  if (RAND_bytes(bytes, sizeof bytes) != 1)
    throw std::runtime_error("RAND_bytes failed: no session token");
  return to_hex(bytes, sizeof bytes);
}

Station::Station(const GroundStationParams& params, StationOptions options)
    : params_(params),
      options_(std::move(options)),
      policy_(policy_for_bind(options_.bind_address, options_.token)),
      state_(params),
      camera_(params.jpeg_quality),
      diag_(params.jpeg_quality) {
  // Every command needs the token, on loopback too (no token was asked there, so any
  // page the operator's browser opened could post commands). On loopback the page may fetch it
  // from GET /api/session; elsewhere the operator types it or opens the printed URL.
  if (policy_.loopback_only && policy_.token.empty()) policy_.token = make_session_token();
  if (policy_.token.size() < 16)
    throw std::runtime_error("serving " + options_.bind_address +
                             " needs a session token of at least 16 characters");
  policy_.require_token = true;
  if (options_.key) builder_.emplace(options_.sender, *options_.key, params_.vehicle_id);
}

Station::~Station() { stop(); }

void Station::attach(Node& node) {
  // StationState runs on the steady clock; the wall clock only where a vehicle's stamp is
  // compared with it (clock offset, latencies).
  node.on<autonomy_status_t>(params_.status_channel, [this](const autonomy_status_t& m) {
    std::lock_guard<std::mutex> lock(state_mutex_);
    state_.on_status(m, steady_utime(), wall_utime());
  });
  node.on<target_t>(params_.target_channel, [this](const target_t& m) {
    std::lock_guard<std::mutex> lock(state_mutex_);
    state_.on_target(m, steady_utime());
  });
  node.on<process_status_t>(params_.process_channel, [this](const process_status_t& m) {
    std::lock_guard<std::mutex> lock(state_mutex_);
    state_.on_process_status(m, steady_utime(), wall_utime());
  });
  node.on<node_status_t>(params_.node_status_channel, [this](const node_status_t& m) {
    std::lock_guard<std::mutex> lock(state_mutex_);
    state_.on_node_status(m, steady_utime());
  });
  node.on<autopilot_status_t>(params_.autopilot_channel, [this](const autopilot_status_t& m) {
    std::lock_guard<std::mutex> lock(state_mutex_);
    state_.on_autopilot_status(m, steady_utime());
  });
  node.on<pose_t>(params_.pose_channel, [this](const pose_t& m) {
    std::lock_guard<std::mutex> lock(state_mutex_);
    state_.on_pose(m, steady_utime());
  });
  auto video = [this](const std::string& channel, FrameStore& store) {
    return [this, channel, &store](const image_t& m) {
      {
        std::lock_guard<std::mutex> lock(state_mutex_);
        state_.on_frame(channel, m.utime, steady_utime(), wall_utime());
      }
      store.put(std::make_shared<const image_t>(m));
    };
  };
  node.on_latest<image_t>(params_.camera_channel, video(params_.camera_channel, camera_));
  node.on_latest<image_t>(params_.diag_channel, video(params_.diag_channel, diag_));
  // Node::every runs on the steady clock (a step of the system clock froze this timer).
  node.every(0.02, [this, &node](int64_t) { publish_pending(node, steady_utime()); });
}

void Station::publish_pending(Node& node, int64_t now_utime) {
  lcm_loop_utime_ = now_utime;
  std::deque<operator_cmd_t> out;
  {
    std::lock_guard<std::mutex> lock(command_mutex_);
    out.swap(pending_commands_);
  }
  for (const auto& cmd : out) {
    node.publish(params_.command_channel, cmd);
    ++commands_published_;
    spdlog::info("ground_station: sent {} seq {}", command_name(cmd.command), cmd.seq);
  }
}

std::string Station::station_json(int64_t now_utime) const {
  JsonWriter w;
  w.begin_object();
  w.field("commands_enabled", builder_.has_value());
  w.field("token_required", policy_.require_token);
  w.field("token_from_server", policy_.loopback_only && !options_.require_token);
  w.field("sender", options_.sender);
  w.field("bind", options_.bind_address);
  const int64_t tick = lcm_loop_utime_;
  w.field("lcm_loop_age_s", tick > 0 ? (now_utime - tick) * 1e-6 : -1.0);
  w.field("camera_channel", params_.camera_channel);
  w.field("diag_channel", params_.diag_channel);
  w.field("status_channel", params_.status_channel);
  w.field("commands_published", static_cast<uint64_t>(commands_published_));
  w.field("commands_refused", static_cast<uint64_t>(commands_refused_));
  w.end_object();
  return w.str();
}

std::shared_ptr<const std::string> Station::state_json(int64_t now_utime) {
  std::lock_guard<std::mutex> lock(state_mutex_);
  if (!state_cache_ || now_utime - state_cache_utime_ > kStateCacheUs ||
      now_utime < state_cache_utime_) {
    state_cache_ =
        std::make_shared<const std::string>(state_.to_json(now_utime, station_json(now_utime)));
    state_cache_utime_ = now_utime;
  }
  return state_cache_;
}

StationCounters Station::counters() const {
  StationCounters c;
  c.http_requests = http_requests_;
  c.commands_published = commands_published_;
  c.commands_refused = commands_refused_;
  c.commands_without_session = commands_without_session_;
  if (server_) {
    const HttpGateCounters g = server_->gate_counters();
    c.connections_over_limit = g.queue_full + g.pending_dropped;
    c.heads_timed_out = g.heads_timed_out;
    c.heads_too_large = g.heads_too_large;
  }
  return c;
}

void Station::setup_routes() {
  auto& svr = *server_;
  svr.set_pre_routing_handler([this](const httplib::Request&, httplib::Response&) {
    ++http_requests_;
    return httplib::Server::HandlerResponse::Unhandled;
  });

  svr.Get("/api/state", [this](const httplib::Request&, httplib::Response& res) {
    json_reply(res, 200, *state_json(steady_utime()));
  });

  // The page on loopback asks for the session token here. Only a same-origin script can read
  // the answer (no CORS header is ever sent), the Host must be a loopback name (DNS
  // rebinding), and no framing is allowed (X-Frame-Options): another page cannot get it.
  svr.Get("/api/session", [this](const httplib::Request& req, httplib::Response& res) {
    AccessPolicy no_token = policy_;
    no_token.require_token = false;
    const Access access = check_command_access(no_token, plain_headers(req));
    if (!policy_.loopback_only || options_.require_token || access != Access::kAllowed) {
      json_reply(res, 403,
                 error_json(access != Access::kAllowed
                                ? access_name(access)
                                : "the session token is not handed out here: type it in"));
      return;
    }
    JsonWriter w;
    w.begin_object().field("ok", true).field("token", policy_.token).end_object();
    json_reply(res, 200, w.str());
  });

  auto frame_route = [this](FrameStore& store) {
    return [this, &store](const httplib::Request& req, httplib::Response& res) {
      uint64_t after = 0;
      if (req.has_param("after"))
        after = std::strtoull(req.get_param_value("after").c_str(), nullptr, 10);
      std::string error;
      const auto jpeg = store.jpeg_after(after, params_.frame_wait_s, &error);
      res.set_header("Cache-Control", "no-store");
      if (!jpeg) {
        res.status = 204;  // nothing yet: the page retries
        res.set_header("X-Frame-Error", error);
        return;
      }
      res.set_header("X-Frame-Seq", std::to_string(jpeg->seq));
      res.set_header("X-Frame-Utime", std::to_string(jpeg->utime));
      // The JPEG is shared by all clients; the response holds a reference, not a copy per
      // client queue.
      const auto bytes = jpeg->bytes;
      res.set_content_provider(bytes->size(), "image/jpeg",
                               [bytes](size_t offset, size_t length, httplib::DataSink& sink) {
                                 return sink.write(bytes->data() + offset, length);
                               });
    };
  };
  svr.Get("/api/frame/camera", frame_route(camera_));
  svr.Get("/api/frame/diag", frame_route(diag_));

  svr.Post("/api/command", [this](const httplib::Request& req, httplib::Response& res) {
    const Access access = check_command_access(policy_, plain_headers(req));
    if (access != Access::kAllowed) {
      ++commands_refused_;
      spdlog::warn("ground_station: command request from {} refused: {}", req.remote_addr,
                   access_name(access));
      json_reply(res, 403, error_json(access_name(access)));
      return;
    }
    std::map<std::string, std::string> fields;
    for (const auto& [k, v] : req.params) fields.emplace(k, v);
    const ParsedCommand parsed = parse_command_request(fields, params_.nudge_max_m);
    if (!parsed.request) {
      ++commands_refused_;
      json_reply(res, 400, error_json(parsed.error));
      return;
    }
    std::lock_guard<std::mutex> lock(command_mutex_);
    if (!builder_) {
      ++commands_refused_;
      json_reply(res, 503, error_json("no key file: this ground station is view-only"));
      return;
    }
    if (pending_commands_.size() >= kMaxPendingCommands) {
      ++commands_refused_;
      json_reply(res, 503, error_json("command queue full (LCM loop not running?)"));
      return;
    }
    // Signed for the session the vehicle announced: without one, the vehicle would refuse it
    // (and the operator would see "sent"), so say so now.
    int64_t session = 0;
    {
      std::lock_guard<std::mutex> state_lock(state_mutex_);
      session = state_.vehicle_session();
    }
    if (session == 0) {
      ++commands_refused_;
      ++commands_without_session_;
      json_reply(res, 503,
                 error_json("vehicle '" + params_.vehicle_id +
                            "' not heard: no AUTONOMY_STATUS with its command session "
                            "(autonomy down, link lost, no key there, or another vehicle_id)"));
      return;
    }
    const operator_cmd_t cmd = builder_->build(*parsed.request, session, wall_utime());
    pending_commands_.push_back(cmd);
    {
      std::lock_guard<std::mutex> state_lock(state_mutex_);
      state_.on_command_sent(command_name(cmd.command), cmd.seq, session, steady_utime());
    }
    JsonWriter w;
    w.begin_object().field("ok", true).field("command", command_name(cmd.command));
    w.field("seq", cmd.seq).end_object();
    json_reply(res, 200, w.str());
  });

  if (!options_.web_dir.empty() && !svr.set_mount_point("/", options_.web_dir))
    throw std::runtime_error("web folder '" + options_.web_dir + "' not found");
}

int Station::start() {
  if (server_) throw std::runtime_error("ground station server already started");
  HttpLimits limits;
  limits.workers = params_.http_threads;
  limits.command_workers = params_.command_threads;
  limits.max_queued = static_cast<size_t>(params_.max_queued_connections);
  limits.max_pending_heads = static_cast<size_t>(params_.max_pending_heads);
  limits.io_timeout_s = params_.client_timeout_s;
  limits.idle_timeout_s = params_.client_timeout_s;
  limits.head_deadline_s = params_.head_deadline_s;
  limits.request_deadline_s = params_.request_deadline_s;
  limits.max_header_count = static_cast<size_t>(params_.max_header_count);
  limits.max_head_bytes = static_cast<size_t>(params_.max_head_bytes);
  limits.max_payload_bytes = static_cast<size_t>(params_.max_payload_bytes);
  server_ = std::make_unique<HardenedServer>(limits);
  // On every response, the page's and errors alike: never inside another site's frame
  // (clickjacking the command buttons), no MIME sniffing, no referrer with the token fragment.
  server_->set_default_headers({{"X-Frame-Options", "DENY"},
                                {"Content-Security-Policy", "frame-ancestors 'none'"},
                                {"X-Content-Type-Options", "nosniff"},
                                {"Referrer-Policy", "no-referrer"}});
  setup_routes();
  const int port = options_.port >= 0 ? options_.port : params_.http_port;
  int bound = -1;
  if (port == 0) {
    bound = server_->bind_to_any_port(options_.bind_address);
  } else if (server_->bind_to_port(options_.bind_address, port)) {
    bound = port;
  }
  if (bound <= 0)
    throw std::runtime_error("cannot listen on " + options_.bind_address + ":" +
                             std::to_string(port) + " (address in use or not local?)");
  server_->widen_backlog(128);
  server_thread_ = std::thread([this] { server_->listen_after_bind(); });
  return bound;
}

void Station::stop() {
  camera_.wake_all();
  diag_.wake_all();
  if (server_) server_->stop();
  if (server_thread_.joinable()) server_thread_.join();
  if (server_) server_->shutdown_all();
  server_.reset();
}

}  // namespace alight::ground_station
