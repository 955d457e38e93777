#pragma once
// The head of an HTTP/1.1 request as it arrives, byte by byte, from an untrusted client: where it
// ends, whether it stays within the limits (head size, header count), and what the server's gate
// needs to route it before any worker is involved (the request line, a command's
// Content-Length). Pure: no sockets, no clock; the server's gate feeds it what recv() returned.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace alight::ground_station {

class HeadReader {
 public:
  enum class State { kMore, kComplete, kTooLarge, kTooManyHeaders };

  HeadReader(size_t max_head_bytes, size_t max_header_count)
      : max_bytes_(max_head_bytes), max_headers_(max_header_count) {}

  /// Consumes bytes of the head; returns how many of `n` belong to it (the rest is body or the
  /// next request). Once the state is not kMore, consumes nothing more.
  size_t feed(const char* data, size_t n);
  State state() const { return state_; }
  /// The head so far (request line, headers and the empty line, as received).
  const std::string& head() const { return head_; }
  std::string request_line() const;
  /// Content-Length of the complete head: 0 when absent, nullopt when malformed, repeated with
  /// different values, or combined with Transfer-Encoding (the body's end is then unknown).
  std::optional<uint64_t> content_length() const;
  void reset();

 private:
  size_t max_bytes_;
  size_t max_headers_;
  State state_ = State::kMore;
  std::string head_;
  size_t lines_ = 0;       // complete lines so far
  size_t line_start_ = 0;  // offset of the current line in head_
};

/// True for the request line of a command: "POST /api/command" followed by a space or a query.
bool is_command_request_line(const std::string& request_line);

}  // namespace alight::ground_station
