#include "link/connections.hpp"

#include <algorithm>
#include <cassert>

namespace alight::link {

Admission::Admission(size_t max_pending, int64_t handshake_timeout_us)
    : max_pending_(max_pending), timeout_us_(handshake_timeout_us) {
  // Programmer invariant: constants and a validated --timeout.
  assert(max_pending_ >= 1 && timeout_us_ > 0);
}

std::optional<uint64_t> Admission::add(uint64_t id, int64_t now_us) {
  std::optional<uint64_t> evicted;
  if (pending_.size() >= max_pending_) {
    const auto oldest = std::min_element(pending_.begin(), pending_.end(), [](auto& a, auto& b) {
      return a.second < b.second || (a.second == b.second && a.first < b.first);
    });
    evicted = oldest->first;
    pending_.erase(oldest);
  }
  pending_[id] = now_us;
  return evicted;
}

std::optional<uint64_t> Admission::authenticated(uint64_t id) {
  // Programmer invariant: only a pending connection can complete its handshake.
  assert(pending_.count(id) == 1);
  pending_.erase(id);
  const std::optional<uint64_t> previous = session_;
  session_ = id;
  return previous;
}

void Admission::remove(uint64_t id) {
  pending_.erase(id);
  if (session_ == id) session_.reset();
}

std::vector<uint64_t> Admission::expired(int64_t now_us) const {
  std::vector<uint64_t> out;
  for (const auto& [id, since] : pending_)
    if (now_us - since > timeout_us_) out.push_back(id);
  return out;
}

std::optional<int64_t> Admission::next_expiry_us() const {
  std::optional<int64_t> t;
  for (const auto& [id, since] : pending_)
    if (!t || since + timeout_us_ < *t) t = since + timeout_us_;
  return t;
}

Backoff::Backoff(int64_t initial_us, int64_t max_us)
    : initial_us_(initial_us), max_us_(max_us), delay_us_(initial_us) {
  // Programmer invariant: constants.
  assert(initial_us_ > 0 && max_us_ >= initial_us_);
}

int64_t Backoff::failed() {
  const int64_t d = delay_us_;
  delay_us_ = std::min(max_us_, delay_us_ * 2);
  return d;
}

}  // namespace alight::link
