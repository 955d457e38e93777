#include "ground_station/http_head.hpp"

#include <cctype>

namespace alight::ground_station {

namespace {
std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}
std::string trim(const std::string& s) {
  size_t b = 0, e = s.size();
  while (b < e && (s[b] == ' ' || s[b] == '\t')) ++b;
  while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t' || s[e - 1] == '\r')) --e;
  return s.substr(b, e - b);
}
}  // namespace

size_t HeadReader::feed(const char* data, size_t n) {
  size_t used = 0;
  while (used < n && state_ == State::kMore) {
    const char c = data[used++];
    head_ += c;
    if (head_.size() > max_bytes_) {
      state_ = State::kTooLarge;
      break;
    }
    if (c != '\n') continue;
    const size_t len = head_.size() - line_start_;  // including '\n'
    const bool empty = len == 1 || (len == 2 && head_[line_start_] == '\r');
    line_start_ = head_.size();
    if (empty && lines_ > 0) {
      state_ = State::kComplete;
      break;
    }
    if (empty) continue;  // RFC 9112 2.2: a server should ignore empty lines before the request
    ++lines_;
    if (lines_ > max_headers_ + 1) state_ = State::kTooManyHeaders;  // + the request line
  }
  return used;
}

std::string HeadReader::request_line() const {
  size_t b = 0;
  while (b < head_.size() && (head_[b] == '\r' || head_[b] == '\n')) ++b;
  const size_t e = head_.find('\n', b);
  std::string line = head_.substr(b, e == std::string::npos ? std::string::npos : e - b);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return line;
}

std::optional<uint64_t> HeadReader::content_length() const {
  std::optional<uint64_t> length;
  size_t pos = head_.find('\n');
  while (pos != std::string::npos && pos + 1 < head_.size()) {
    const size_t start = pos + 1;
    pos = head_.find('\n', start);
    const std::string line = head_.substr(start, pos == std::string::npos ? pos : pos - start);
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string name = lower(trim(line.substr(0, colon)));
    const std::string value = trim(line.substr(colon + 1));
    if (name == "transfer-encoding") return std::nullopt;
    if (name != "content-length") continue;
    if (value.empty() || value.size() > 18) return std::nullopt;
    uint64_t v = 0;
    for (char c : value) {
      if (c < '0' || c > '9') return std::nullopt;
      v = v * 10 + static_cast<uint64_t>(c - '0');
    }
    if (length && *length != v) return std::nullopt;
    length = v;
  }
  return length.value_or(0);
}

void HeadReader::reset() {
  state_ = State::kMore;
  head_.clear();
  lines_ = 0;
  line_start_ = 0;
}

bool is_command_request_line(const std::string& line) {
  static const std::string prefix = "POST /api/command";
  if (line.compare(0, prefix.size(), prefix) != 0 || line.size() == prefix.size()) return false;
  const char next = line[prefix.size()];
  return next == ' ' || next == '?';
}

}  // namespace alight::ground_station
