#pragma once
// The queue between LCM and a node's handlers (common/node.hpp): messages of several
// subscriptions in one arrival order, each subscription holding at most its own capacity.
//
// One queue for all subscriptions, not one per subscription, so a handler sees the messages of
// different channels in the order they arrived (the vision pairs frames with poses by that
// order). Per-subscription capacities bound memory: a consumer that falls behind a 60 Hz camera
// holds at most `capacity` frames, not what an unbounded queue would gather, and every message
// refused for a full queue is counted (NODE_STATUS `dropped`), where LCM's own queue drops the
// newest silently. Like LCM, it refuses the newest: the messages already waiting keep their
// order and none is delivered twice. Pure: no LCM, no clock.

#include <cassert>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <utility>
#include <vector>

namespace alight {

template <class Item>
class Inbox {
 public:
  /// A subscription that may hold up to `capacity` (>= 1) waiting messages; returns its id.
  size_t add_source(size_t capacity) {
    assert(capacity >= 1);
    sources_.push_back(Source{capacity, 0, 0});
    return sources_.size() - 1;
  }
  /// Queues `item` of `source` behind every waiting message; false (and counted as dropped) when
  /// that source already holds its capacity.
  bool push(size_t source, Item item) {
    Source& s = sources_.at(source);
    if (s.waiting >= s.capacity) {
      ++s.dropped;
      return false;
    }
    ++s.waiting;
    queue_.push_back({source, std::move(item)});
    return true;
  }
  /// The oldest waiting message and its source; nullopt when none waits.
  std::optional<std::pair<size_t, Item>> pop() {
    if (queue_.empty()) return std::nullopt;
    std::pair<size_t, Item> front = std::move(queue_.front());
    queue_.pop_front();
    --sources_[front.first].waiting;
    return front;
  }
  size_t size() const { return queue_.size(); }
  size_t waiting(size_t source) const { return sources_.at(source).waiting; }
  uint64_t dropped(size_t source) const { return sources_.at(source).dropped; }
  size_t capacity(size_t source) const { return sources_.at(source).capacity; }

 private:
  struct Source {
    size_t capacity;
    size_t waiting;
    uint64_t dropped;
  };
  std::vector<Source> sources_;
  std::deque<std::pair<size_t, Item>> queue_;
};

}  // namespace alight
