#include "link/cli.hpp"

#include <CLI/CLI.hpp>

namespace alight::link {

void add_options(CLI::App& app, RawOptions& raw, std::string& key_file) {
  app.add_option("--listen", raw.listen,
                 "ADDR:PORT: the vehicle side; wait for the peer here (e.g. 0.0.0.0:7670)");
  app.add_option("--connect", raw.connect,
                 "HOST:PORT: the ground side; connect to the vehicle's link there, and again "
                 "whenever the connection ends");
  app.add_option("--key", key_file, "Link key file (scripts/make-key), the same on both sides")
      ->required();
  app.add_option("--send", raw.send,
                 "CH[,CH...]: channels read from this bus and sent to the peer (repeatable)");
  app.add_option("--receive", raw.receive,
                 "CH[,CH...]: channels taken from the peer and published on this bus; anything "
                 "else from the peer is refused (repeatable)");
  app.add_option("--max-rate", raw.max_rate,
                 "CH=HZ: at most HZ messages per second on a channel, either way (repeatable; "
                 "images over Wi-Fi)");
  app.add_option("--timeout", raw.timeout_s,
                 "Seconds a handshake may take and a session may stay silent before the "
                 "connection is ended (default " +
                     std::to_string(static_cast<int>(kDefaultTimeoutS)) + ")");
  app.add_option("--max-frame-bytes", raw.max_frame_bytes,
                 "Largest frame taken from the peer or sent to it, the same on both sides "
                 "(default " +
                     std::to_string(kDefaultMaxFrameBytes) + ")");
}

}  // namespace alight::link
