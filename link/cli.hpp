#pragma once
// alight-link's own options, declared once: the node parses its command line with them, and the
// tests parse the launch files' alight-link commands with them.

#include <string>

#include "link/options.hpp"

namespace CLI {
class App;
}

namespace alight::link {

/// Adds --listen, --connect, --key, --send, --receive, --max-rate, --timeout and
/// --max-frame-bytes to `app`, filling `raw` and `key_file`.
void add_options(CLI::App& app, RawOptions& raw, std::string& key_file);

}  // namespace alight::link
