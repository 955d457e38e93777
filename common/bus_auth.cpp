#include "common/bus_auth.hpp"

#include <openssl/core_names.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/params.h>
#include <openssl/rand.h>
#include <openssl/sha.h>

#include <algorithm>
#include <cassert>
#include <cstring>
#include <stdexcept>

#include "common/operator_auth.hpp"

namespace alight::bus {

namespace {

void put_be(uint8_t* out, uint64_t v, int n) {
  for (int i = 0; i < n; ++i) out[i] = static_cast<uint8_t>(v >> (8 * (n - 1 - i)));
}

uint64_t get_be(const uint8_t* in, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | in[i];
  return v;
}

// The trailer's first 18 bytes (source, counter, key id, flags): what the tag covers of it.
std::array<uint8_t, 18> header_bytes(const Trailer& t) {
  std::array<uint8_t, 18> h{};
  put_be(h.data(), t.source, 8);
  put_be(h.data() + 8, t.counter, 8);
  h[16] = t.key_id;
  h[17] = t.flags;
  return h;
}

uint8_t key_id_of(const std::vector<uint8_t>& bytes) {
  std::array<uint8_t, SHA256_DIGEST_LENGTH> d{};
  SHA256(bytes.data(), bytes.size(), d.data());
  return d[0] == 0 ? 1 : d[0];
}

}  // namespace

BusKey make_bus_key(std::vector<uint8_t> bytes) {
  BusKey k;
  k.id = key_id_of(bytes);
  k.bytes = std::move(bytes);
  return k;
}

BusKey load_bus_key(const std::string& path, std::vector<std::string>* warnings) {
  LoadedKey loaded = load_key_file(path);
  if (warnings) warnings->insert(warnings->end(), loaded.warnings.begin(), loaded.warnings.end());
  return make_bus_key(std::move(loaded.key.bytes));
}

Received split(const void* data, size_t size) {
  const auto* p = static_cast<const uint8_t*>(data);
  Received r;
  r.payload = std::span<const uint8_t>(p, size);
  if (size < kTrailerBytes || !std::equal(kMagic.begin(), kMagic.end(), p + size - kMagic.size()))
    return r;
  const uint8_t* t = p + size - kTrailerBytes;
  Trailer tr;
  tr.source = get_be(t, 8);
  tr.counter = get_be(t + 8, 8);
  tr.key_id = t[16];
  tr.flags = t[17];
  std::memcpy(tr.tag.data(), t + 18, kTagBytes);
  r.payload = std::span<const uint8_t>(p, size - kTrailerBytes);
  r.trailer = tr;
  return r;
}

std::array<uint8_t, kTagBytes> compute_tag(const BusKey& key, const std::string& channel,
                                           std::span<const uint8_t> payload, const Trailer& t) {
  // Programmer invariant: keys come from load_bus_key / make_bus_key.
  assert(!key.bytes.empty());
  static EVP_MAC* const mac = EVP_MAC_fetch(nullptr, "HMAC", nullptr);
  EVP_MAC_CTX* ctx = mac ? EVP_MAC_CTX_new(mac) : nullptr;
  char digest[] = "SHA256";
  const OSSL_PARAM params[] = {OSSL_PARAM_construct_utf8_string("digest", digest, 0),
                               OSSL_PARAM_construct_end()};
  const auto header = header_bytes(t);
  const uint8_t zero = 0;
  size_t len = 0;
  std::array<uint8_t, EVP_MAX_MD_SIZE> full{};
  const bool ok =
      ctx && EVP_MAC_init(ctx, key.bytes.data(), key.bytes.size(), params) == 1 &&
      EVP_MAC_update(ctx, kMagic.data(), kMagic.size()) == 1 &&
      EVP_MAC_update(ctx, reinterpret_cast<const uint8_t*>(channel.data()), channel.size()) == 1 &&
      EVP_MAC_update(ctx, &zero, 1) == 1 &&
      EVP_MAC_update(ctx, payload.data(), payload.size()) == 1 &&
      EVP_MAC_update(ctx, header.data(), header.size()) == 1 &&
      EVP_MAC_final(ctx, full.data(), &len, full.size()) == 1 && len >= kTagBytes;
  EVP_MAC_CTX_free(ctx);
  if (!ok) throw std::runtime_error("bus_auth: OpenSSL HMAC-SHA256 failed");
  std::array<uint8_t, kTagBytes> tag{};
  std::memcpy(tag.data(), full.data(), kTagBytes);
  return tag;
}

Sealer::Sealer(uint64_t source, std::optional<BusKey> key)
    : source_(source), key_(std::move(key)) {}

void Sealer::seal(std::vector<uint8_t>& bytes, const std::string& channel, int64_t bus_time_us) {
  counter_ =
      std::max<uint64_t>(counter_ + 1, static_cast<uint64_t>(std::max<int64_t>(0, bus_time_us)));
  Trailer t;
  t.source = source_;
  t.counter = counter_;
  if (key_) {
    t.key_id = key_->id;
    t.tag = compute_tag(*key_, channel, bytes, t);
  }
  const size_t at = bytes.size();
  bytes.resize(at + kTrailerBytes);
  uint8_t* out = bytes.data() + at;
  const auto header = header_bytes(t);
  std::memcpy(out, header.data(), header.size());
  std::memcpy(out + 18, t.tag.data(), kTagBytes);
  std::memcpy(out + 34, kMagic.data(), kMagic.size());
}

uint64_t draw_source_id() {
  uint64_t id = 0;
  while (id == 0)
    if (RAND_bytes(reinterpret_cast<unsigned char*>(&id), sizeof id) != 1)
      throw std::runtime_error("bus_auth: no random source id (RAND_bytes failed)");
  return id;
}

const char* verdict_name(Verdict v) {
  switch (v) {
    case Verdict::kAccepted:
      return "accepted";
    case Verdict::kNewOwner:
      return "accepted from a new publisher";
    case Verdict::kUnsigned:
      return "unsigned on a signed bus";
    case Verdict::kWrongKey:
      return "signed with another key";
    case Verdict::kBadTag:
      return "signature does not match";
    case Verdict::kReplayed:
      return "counter not above the publisher's last (replayed)";
    case Verdict::kStale:
      return "a new publisher far behind the bus time (a recording replayed)";
    case Verdict::kSecondPublisher:
      return "a second publisher while the channel's publisher is alive";
  }
  return "?";
}

Verdict Gatekeeper::authenticate(const std::string& channel, const Received& msg) const {
  if (!key_) return Verdict::kAccepted;
  if (!msg.trailer || msg.trailer->key_id == 0) return Verdict::kUnsigned;
  if (msg.trailer->key_id != key_->id) return Verdict::kWrongKey;
  const auto tag = compute_tag(*key_, channel, msg.payload, *msg.trailer);
  if (CRYPTO_memcmp(tag.data(), msg.trailer->tag.data(), kTagBytes) != 0) return Verdict::kBadTag;
  return Verdict::kAccepted;
}

int64_t Gatekeeper::silent_after_us(const Source& s) {
  // Ten of its usual gaps, within [0.2 s, 1 s]: a 100 Hz pose is taken over 0.2 s after it
  // stops, a 1 Hz status after 1 s; a publisher seen once is given the full second.
  constexpr int64_t kMin = 200'000, kMax = 1'000'000;
  if (s.n < 2) return kMax;
  return std::clamp(static_cast<int64_t>(10.0 * s.interval_us), kMin, kMax);
}

void Gatekeeper::remember(Channel& c, uint64_t id, const Received& msg, int64_t steady_us) {
  auto it = c.sources.find(id);
  if (it == c.sources.end()) {
    if (c.sources.size() >= kMaxSourcesPerChannel) {
      // Forget the longest-silent source that is not the owner.
      auto victim = c.sources.end();
      for (auto s = c.sources.begin(); s != c.sources.end(); ++s)
        if ((!c.owner || s->first != *c.owner) &&
            (victim == c.sources.end() || s->second.last_steady_us < victim->second.last_steady_us))
          victim = s;
      if (victim != c.sources.end()) c.sources.erase(victim);
    }
    it = c.sources.emplace(id, Source{}).first;
  }
  Source& s = it->second;
  if (s.n > 0) {
    const double gap = static_cast<double>(std::max<int64_t>(0, steady_us - s.last_steady_us));
    s.interval_us = s.n == 1 ? gap : 0.9 * s.interval_us + 0.1 * gap;
  }
  ++s.n;
  s.last_steady_us = steady_us;
  if (msg.trailer) s.last_counter = msg.trailer->counter;
}

Verdict Gatekeeper::check(const std::string& channel, const Received& msg, int64_t steady_us,
                          bool single_publisher) {
  Channel& c = channels_[channel];
  Verdict v = authenticate(channel, msg);
  if (v != Verdict::kAccepted) {
    ++c.stats.rejected_auth;
    return v;
  }
  const uint64_t id = msg.trailer ? msg.trailer->source : 0;
  const auto known = c.sources.find(id);
  if (msg.trailer && id != 0) {
    if (known != c.sources.end() && known->second.n > 0 &&
        msg.trailer->counter <= known->second.last_counter) {
      ++c.stats.rejected_auth;
      return Verdict::kReplayed;
    }
    if (key_ && known == c.sources.end() && bus_time_us_ > 0 &&
        static_cast<int64_t>(msg.trailer->counter) < bus_time_us_ - kMaxStaleUs) {
      ++c.stats.rejected_auth;
      return Verdict::kStale;
    }
  }
  if (single_publisher && c.owner && *c.owner != id) {
    const auto owner = c.sources.find(*c.owner);
    const bool owner_alive = owner != c.sources.end() && steady_us - owner->second.last_steady_us <
                                                             silent_after_us(owner->second);
    if (owner_alive) {
      ++c.stats.second_publisher;
      if (c.stats.second_publisher == 1 ||
          steady_us - c.stats.last_second_publisher_steady_us > kContestGapUs)
        c.stats.contest_since_steady_us = steady_us;
      c.stats.last_second_publisher_steady_us = steady_us;
      // The intruder is remembered (its counters too), so its replays are refused as such.
      remember(c, id, msg, steady_us);
      return Verdict::kSecondPublisher;
    }
    ++c.stats.owner_changes;
    v = Verdict::kNewOwner;
    c.owner = id;
  } else if (!c.owner) {
    v = Verdict::kNewOwner;
    c.owner = id;
  }
  c.stats.owner = id;
  remember(c, id, msg, steady_us);
  if (msg.trailer)
    bus_time_us_ = std::max<int64_t>(bus_time_us_, static_cast<int64_t>(msg.trailer->counter));
  return v;
}

const ChannelAuthStats& Gatekeeper::stats(const std::string& channel) const {
  static const ChannelAuthStats kNone;
  const auto it = channels_.find(channel);
  return it == channels_.end() ? kNone : it->second.stats;
}

int64_t Gatekeeper::contest_span_us(const std::string& channel, int64_t steady_us) const {
  const auto& s = stats(channel);
  if (s.second_publisher == 0 || steady_us - s.last_second_publisher_steady_us > kContestGapUs)
    return 0;
  return s.last_second_publisher_steady_us - s.contest_since_steady_us;
}

size_t Gatekeeper::known_sources(const std::string& channel) const {
  const auto it = channels_.find(channel);
  return it == channels_.end() ? 0 : it->second.sources.size();
}

bool Gatekeeper::contested(const std::string& channel, int64_t steady_us, int64_t window_us) const {
  const auto& s = stats(channel);
  return s.second_publisher > 0 && steady_us - s.last_second_publisher_steady_us < window_us;
}

}  // namespace alight::bus
