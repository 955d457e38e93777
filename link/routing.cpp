#include "link/routing.hpp"

#include <cassert>
#include <cmath>

namespace alight::link {

RateLimit::RateLimit(double max_rate_hz) {
  // Programmer invariant: rates come from parse_rates (finite, >= 0).
  assert(std::isfinite(max_rate_hz) && max_rate_hz >= 0);
  period_us_ = max_rate_hz > 0 ? static_cast<int64_t>(std::llround(1e6 / max_rate_hz)) : 0;
}

void RateLimit::sent(int64_t now_us) {
  if (period_us_ == 0) return;
  // Within a period of the schedule: keep it (the average rate is the limit even when the
  // messages come with jitter). Further behind: nothing was sent for a while, start afresh.
  if (started_ && now_us - next_us_ < period_us_)
    next_us_ += period_us_;
  else
    next_us_ = now_us + period_us_;
  started_ = true;
}

void Outbox::add_channel(const std::string& channel, SendMode mode, size_t capacity,
                         double max_rate_hz) {
  // Programmer invariant: the node adds each channel of its validated options once.
  assert(!has_channel(channel) && capacity >= 1);
  index_[channel] = channels_.size();
  Channel c;
  c.name = channel;
  c.mode = mode;
  c.capacity = mode == SendMode::kNewest ? 1 : capacity;
  c.rate = RateLimit(max_rate_hz);
  channels_.push_back(std::move(c));
}

void Outbox::offer(const std::string& channel, std::vector<uint8_t> payload) {
  const auto it = index_.find(channel);
  // Programmer invariant: the node offers only the channels it subscribed for the outbox.
  assert(it != index_.end());
  Channel& c = channels_[it->second];
  ++c.stats.offered;
  if (c.waiting.size() >= c.capacity) {
    c.waiting.pop_front();
    ++(c.mode == SendMode::kNewest ? c.stats.superseded : c.stats.overflowed);
  }
  c.waiting.push_back(std::move(payload));
}

std::optional<Outbox::Item> Outbox::next(int64_t now_us) {
  for (size_t k = 0; k < channels_.size(); ++k) {
    const size_t i = (turn_ + k) % channels_.size();
    Channel& c = channels_[i];
    if (c.waiting.empty() || !c.rate.allows(now_us)) continue;
    Item item{c.name, std::move(c.waiting.front())};
    c.waiting.pop_front();
    c.rate.sent(now_us);
    ++c.stats.sent;
    turn_ = i + 1;
    return item;
  }
  return std::nullopt;
}

std::optional<int64_t> Outbox::next_due_us(int64_t now_us) const {
  std::optional<int64_t> due;
  for (const auto& c : channels_) {
    if (c.waiting.empty() || c.rate.allows(now_us)) continue;
    if (!due || c.rate.next_allowed_us() < *due) due = c.rate.next_allowed_us();
  }
  return due;
}

void Outbox::clear() {
  for (auto& c : channels_) {
    c.stats.discarded += c.waiting.size();
    c.waiting.clear();
  }
}

size_t Outbox::waiting() const {
  size_t n = 0;
  for (const auto& c : channels_) n += c.waiting.size();
  return n;
}

const OutboxStats& Outbox::stats(const std::string& channel) const {
  static const OutboxStats kNone;
  const auto it = index_.find(channel);
  return it == index_.end() ? kNone : channels_[it->second].stats;
}

OutboxStats Outbox::total() const {
  OutboxStats t;
  for (const auto& c : channels_) {
    t.offered += c.stats.offered;
    t.sent += c.stats.sent;
    t.superseded += c.stats.superseded;
    t.overflowed += c.stats.overflowed;
    t.discarded += c.stats.discarded;
  }
  return t;
}

const char* admit_name(Admit a) {
  switch (a) {
    case Admit::kAccepted:
      return "accepted";
    case Admit::kNotListed:
      return "not a --receive channel";
    case Admit::kOverRate:
      return "beyond its --max-rate";
  }
  return "unknown";
}

void ReceiveFilter::allow(const std::string& channel, double max_rate_hz) {
  rates_[channel] = RateLimit(max_rate_hz);
}

Admit ReceiveFilter::check(const std::string& channel, int64_t now_us) {
  const auto it = rates_.find(channel);
  if (it == rates_.end()) return Admit::kNotListed;
  if (!it->second.allows(now_us)) return Admit::kOverRate;
  it->second.sent(now_us);
  return Admit::kAccepted;
}

}  // namespace alight::link
