// alight-ground-station: the operator's station (paper 4.1). Joins LCM and serves the web page
// with live video, mission state and signed commands. The only file in ground_station/ that
// owns LCM, the command line, the key file and the clock.

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>

#include "common/build_paths.hpp"
#include "common/node.hpp"
#include "common/operator_auth.hpp"
#include "ground_station/params.hpp"
#include "ground_station/station.hpp"

namespace gs = alight::ground_station;

int main(int argc, char** argv) {
  return alight::run_node_main("alight-ground-station", [&]() -> int {
    CLI::App app{"alight ground station: web page with live video, mission state and commands"};
    alight::NodeArgs args;
    args.add_to(app, false);
    std::string bind = "127.0.0.1";
    int port = -1;
    // The page in the source tree this binary was built from.
    std::string key_file,
        web_dir = std::string(alight::build::source_dir()) + "/ground_station/web", sender;
    app.add_option("--bind", bind,
                   "Address to serve the page on (default 127.0.0.1; any other address "
                   "requires the session token printed at start for every command)");
    app.add_option("--port", port, "TCP port (default: http_port of the config, 8080; 0: any)");
    app.add_option("--key-file", key_file,
                   "Shared key for signing OPERATOR_CMD (hex or raw, >= 32 bytes); without it "
                   "the station is view-only");
    app.add_option("--web-dir", web_dir, "Folder of the page (index.html, app.js, style.css)")
        ->check(CLI::ExistingDirectory);
    bool require_token = false;
    app.add_flag("--require-token", require_token,
                 "On loopback, do not hand the session token to the page (GET /api/session): "
                 "it must come from the printed URL (e.g. when reached through an SSH tunnel or "
                 "a proxy)");
    app.add_option("--sender", sender, "Sender id in OPERATOR_CMD (default gs-<hostname>)");
    std::string vehicle_id;
    app.add_option("--vehicle-id", vehicle_id,
                   "Vehicle to command (overrides ground_station.vehicle_id; must equal the "
                   "vehicle's autonomy.vehicle_id)");
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      return app.exit(e);
    }
    args.finalize();
    gs::GroundStationParams params = gs::load_params(args.config);
    if (!vehicle_id.empty()) {
      params.vehicle_id = vehicle_id;
      params.validate();
    }

    gs::StationOptions options;
    options.bind_address = bind;
    options.port = port;
    options.web_dir = web_dir;
    if (sender.empty()) {
      char host[256] = {0};
      ::gethostname(host, sizeof host - 1);
      sender = std::string("gs-") + host;
    }
    options.sender = sender;
    if (!key_file.empty()) {
      alight::LoadedKey loaded = alight::load_key_file(key_file);
      for (const auto& w : loaded.warnings) spdlog::warn("{}", w);
      options.key = std::move(loaded.key);
    } else {
      spdlog::warn("no --key-file: view-only, command buttons are disabled");
    }
    options.token = gs::make_session_token();
    options.require_token = require_token;

    alight::Node node(args, "alight-ground-station");
    gs::Station station(params, options);
    station.attach(node);
    const int bound = station.start();
    const std::string host = bind == "0.0.0.0" ? "<this-host>" : bind;
    if (station.policy().require_token) {
      std::printf("alight-ground-station: serving http://%s:%d/#token=%s\n", host.c_str(), bound,
                  options.token.c_str());
      std::printf("alight-ground-station: session token %s (needed for every command)\n",
                  options.token.c_str());
    } else {
      std::printf("alight-ground-station: serving http://%s:%d/\n", host.c_str(), bound);
    }
    std::fflush(stdout);
    // Node::run() throws "LCM handle failed" when SIGINT interrupts LCM's select() (Debian LCM
    // 1.3.1 returns -1 on EINTR); a signal that asked us to stop is a clean exit.
    while (!node.stopping()) {
      try {
        node.spin_once(100);
      } catch (const std::runtime_error&) {
        if (!node.stopping()) throw;
      }
    }
    spdlog::info("alight-ground-station: shutting down");
    station.stop();
    return 0;
  });
}
