#include "link/protocol.hpp"

#include <openssl/core_names.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>

#include <algorithm>
#include <cassert>
#include <cctype>
#include <cstring>
#include <initializer_list>
#include <stdexcept>

namespace alight::link {

namespace {

constexpr char kSessionLabel[] = "alight-link session";

void put_be(std::vector<uint8_t>& out, uint64_t v, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}

uint64_t get_be(const uint8_t* p, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

std::span<const uint8_t> as_bytes(const char* s, size_t n) {
  return {reinterpret_cast<const uint8_t*>(s), n};
}

// HMAC-SHA256 over the concatenation of `parts`, without copying them into one buffer (a
// frame's payload is an image of hundreds of kilobytes).
std::array<uint8_t, 32> hmac_sha256(std::span<const uint8_t> key,
                                    std::initializer_list<std::span<const uint8_t>> parts) {
  static EVP_MAC* const mac = EVP_MAC_fetch(nullptr, "HMAC", nullptr);
  EVP_MAC_CTX* ctx = mac ? EVP_MAC_CTX_new(mac) : nullptr;
  char digest[] = "SHA256";
  const OSSL_PARAM params[] = {OSSL_PARAM_construct_utf8_string(OSSL_MAC_PARAM_DIGEST, digest, 0),
                               OSSL_PARAM_construct_end()};
  bool ok = ctx && EVP_MAC_init(ctx, key.data(), key.size(), params) == 1;
  for (const auto& p : parts) ok = ok && EVP_MAC_update(ctx, p.data(), p.size()) == 1;
  std::array<uint8_t, 32> out{};
  size_t len = 0;
  ok = ok && EVP_MAC_final(ctx, out.data(), &len, out.size()) == 1 && len == out.size();
  EVP_MAC_CTX_free(ctx);
  // No input can cause this: OpenSSL without HMAC or out of memory.
  if (!ok) throw std::runtime_error("alight-link: OpenSSL HMAC-SHA256 failed");
  return out;
}

std::array<uint8_t, kTagBytes> frame_tag(const SessionKey& key, std::span<const uint8_t> covered) {
  const auto full = hmac_sha256(key, {covered});
  std::array<uint8_t, kTagBytes> tag{};
  std::memcpy(tag.data(), full.data(), kTagBytes);
  return tag;
}

}  // namespace

const char* role_name(Role r) { return r == Role::kVehicle ? "vehicle" : "ground"; }

const char* failure_name(Failure f) {
  switch (f) {
    case Failure::kNone:
      return "none";
    case Failure::kOtherKey:
      return "another key";
    case Failure::kBadTag:
      return "bad tag";
    case Failure::kReflected:
      return "reflected";
    case Failure::kBadCounter:
      return "bad counter";
    case Failure::kBadHello:
      return "bad hello";
    case Failure::kSameRole:
      return "same role";
    case Failure::kSameNonce:
      return "same nonce";
    case Failure::kOversized:
      return "oversized";
    case Failure::kMalformed:
      return "malformed";
    case Failure::kOutOfOrder:
      return "out of order";
  }
  return "unknown";
}

bool is_auth_failure(Failure f) {
  return f == Failure::kOtherKey || f == Failure::kBadTag || f == Failure::kReflected ||
         f == Failure::kBadCounter;
}

std::array<uint8_t, kHelloBytes> encode_hello(const Hello& h) {
  std::array<uint8_t, kHelloBytes> b{};
  std::copy(kHelloMagic.begin(), kHelloMagic.end(), b.begin());
  b[4] = static_cast<uint8_t>(h.role);
  b[5] = h.key_id;
  std::copy(h.nonce.begin(), h.nonce.end(), b.begin() + 8);
  return b;
}

std::optional<Hello> parse_hello(std::span<const uint8_t> b, Failure* why) {
  *why = Failure::kBadHello;
  if (b.size() != kHelloBytes || !std::equal(kHelloMagic.begin(), kHelloMagic.end(), b.begin()))
    return std::nullopt;
  if (b[4] != static_cast<uint8_t>(Role::kVehicle) && b[4] != static_cast<uint8_t>(Role::kGround))
    return std::nullopt;
  if (b[5] == 0 || b[6] != 0 || b[7] != 0) return std::nullopt;
  Hello h;
  h.role = static_cast<Role>(b[4]);
  h.key_id = b[5];
  std::copy(b.begin() + 8, b.end(), h.nonce.begin());
  *why = Failure::kNone;
  return h;
}

SessionKey derive_session_key(const bus::BusKey& link_key, const Nonce& vehicle,
                              const Nonce& ground) {
  return hmac_sha256(link_key.bytes,
                     {as_bytes(kSessionLabel, sizeof kSessionLabel - 1), vehicle, ground});
}

bool valid_channel_name(std::span<const uint8_t> name) {
  return !name.empty() && name.size() <= kMaxChannelBytes &&
         std::all_of(name.begin(), name.end(),
                     [](uint8_t c) { return std::isalnum(c) || c == '_' || c == '-' || c == '/'; });
}

std::vector<uint8_t> seal_frame(const SessionKey& key, FrameType type, Role direction,
                                uint64_t counter, const std::string& channel,
                                std::span<const uint8_t> payload) {
  // Programmer invariant: callers pass channels they validated, and none for control frames.
  assert(channel.size() <= kMaxChannelBytes);
  assert(type == FrameType::kData || (channel.empty() && payload.empty()));
  const size_t length = kFrameOverhead + channel.size() + payload.size();
  std::vector<uint8_t> f;
  f.reserve(4 + length);
  put_be(f, length, 4);
  f.push_back(static_cast<uint8_t>(type));
  f.push_back(static_cast<uint8_t>(direction));
  put_be(f, counter, 8);
  f.push_back(static_cast<uint8_t>(channel.size()));
  f.insert(f.end(), channel.begin(), channel.end());
  f.insert(f.end(), payload.begin(), payload.end());
  const auto tag = frame_tag(key, f);
  f.insert(f.end(), tag.begin(), tag.end());
  return f;
}

Session::Session(bus::BusKey link_key, Role role, const Nonce& nonce, size_t max_frame_bytes)
    : key_(std::move(link_key)), role_(role), nonce_(nonce), max_frame_bytes_(max_frame_bytes) {
  // Programmer invariant: keys come from load_bus_key / make_bus_key, the bound from a validated
  // option.
  assert(!key_.bytes.empty() && key_.id != 0);
  assert(max_frame_bytes_ >= kMinMaxFrameBytes && max_frame_bytes_ <= kMaxMaxFrameBytes);
  unit_.reserve(kHelloBytes);
}

std::array<uint8_t, kHelloBytes> Session::hello() const {
  return encode_hello(Hello{role_, key_.id, nonce_});
}

bool Session::fail(Failure f, std::string why) {
  failure_ = f;
  error_ = std::move(why);
  unit_.clear();
  unit_.shrink_to_fit();
  return false;
}

size_t Session::frame_bound() const {
  return state_ == State::kOpen ? max_frame_bytes_ : kControlFrameLength;
}

bool Session::feed(std::span<const uint8_t> bytes, std::vector<Message>& out) {
  if (failed()) return false;
  stats_.bytes_received += bytes.size();
  size_t i = 0;
  while (i < bytes.size()) {
    // Never more than the unit being read: the buffer holds one hello or one frame at most.
    const size_t take = std::min(unit_need_ - unit_.size(), bytes.size() - i);
    unit_.insert(unit_.end(), bytes.begin() + i, bytes.begin() + i + take);
    i += take;
    if (unit_.size() < unit_need_) break;
    if (state_ == State::kHello) {
      if (!handle_hello()) return false;
      unit_.clear();
      unit_need_ = 4;
      continue;
    }
    if (!have_length_) {
      const size_t length = get_be(unit_.data(), 4);
      if (length > frame_bound()) {
        const std::string what = state_ == State::kOpen
                                     ? "the bound of " + std::to_string(max_frame_bytes_)
                                     : "a READY's " + std::to_string(kControlFrameLength);
        return fail(Failure::kOversized,
                    "a frame of " + std::to_string(length) + " bytes, beyond " + what);
      }
      if (length < kFrameOverhead)
        return fail(Failure::kMalformed,
                    "a frame of " + std::to_string(length) + " bytes, shorter than any frame");
      have_length_ = true;
      unit_need_ = 4 + length;
      unit_.reserve(unit_need_);
      continue;
    }
    if (!handle_frame(out)) return false;
    unit_.clear();
    unit_need_ = 4;
    have_length_ = false;
  }
  return true;
}

bool Session::handle_hello() {
  Failure why = Failure::kNone;
  const auto peer = parse_hello(unit_, &why);
  if (!peer) return fail(why, "not an alight-link hello");
  if (peer->role == role_)
    return fail(Failure::kSameRole, std::string("the peer is a ") + role_name(role_) +
                                        " side too (one side listens, the other connects)");
  if (peer->key_id != key_.id)
    return fail(Failure::kOtherKey, "the peer's link key is another one (key id " +
                                        std::to_string(peer->key_id) + ", ours " +
                                        std::to_string(key_.id) + ")");
  if (peer->nonce == nonce_) return fail(Failure::kSameNonce, "the peer sent our own nonce back");
  session_key_ = role_ == Role::kVehicle ? derive_session_key(key_, nonce_, peer->nonce)
                                         : derive_session_key(key_, peer->nonce, nonce_);
  control_ = seal(FrameType::kReady, "", {});
  state_ = State::kReady;
  return true;
}

bool Session::handle_frame(std::vector<Message>& out) {
  const size_t n = unit_.size();
  const std::span<const uint8_t> covered(unit_.data(), n - kTagBytes);
  const auto expected = frame_tag(session_key_, covered);
  if (CRYPTO_memcmp(expected.data(), unit_.data() + n - kTagBytes, kTagBytes) != 0)
    return fail(Failure::kBadTag,
                state_ == State::kReady
                    ? "the peer's READY does not verify: it does not hold our link key"
                    : "a frame's tag does not verify (altered, forged or from another session)");
  const uint8_t type = unit_[4];
  const uint8_t direction = unit_[5];
  const uint64_t counter = get_be(unit_.data() + 6, 8);
  const size_t channel_len = unit_[14];
  if (direction == static_cast<uint8_t>(role_))
    return fail(Failure::kReflected, "a frame of our own direction came back");
  if (direction != static_cast<uint8_t>(role_ == Role::kVehicle ? Role::kGround : Role::kVehicle))
    return fail(Failure::kMalformed, "a frame of direction " + std::to_string(direction));
  if (counter != next_receive_counter_)
    return fail(Failure::kBadCounter, "counter " + std::to_string(counter) + " where " +
                                          std::to_string(next_receive_counter_) +
                                          " was due (replayed, dropped or reordered)");
  const size_t body = n - 4 - kFrameOverhead;  // channel and payload
  if (channel_len > body) return fail(Failure::kMalformed, "a channel length beyond the frame");
  const size_t payload_len = body - channel_len;
  if (state_ == State::kReady) {
    if (type != static_cast<uint8_t>(FrameType::kReady))
      return fail(Failure::kOutOfOrder, "a frame before the peer's READY");
    if (body != 0) return fail(Failure::kMalformed, "a READY with a body");
    state_ = State::kOpen;
  } else if (type == static_cast<uint8_t>(FrameType::kKeepalive)) {
    if (body != 0) return fail(Failure::kMalformed, "a KEEPALIVE with a body");
  } else if (type == static_cast<uint8_t>(FrameType::kData)) {
    const std::span<const uint8_t> channel(unit_.data() + 15, channel_len);
    if (!valid_channel_name(channel))
      return fail(Failure::kMalformed, "a DATA frame without a valid channel name");
    Message m;
    m.channel.assign(channel.begin(), channel.end());
    m.payload.assign(unit_.begin() + 15 + channel_len,
                     unit_.begin() + 15 + channel_len + payload_len);
    out.push_back(std::move(m));
    ++stats_.data_received;
  } else if (type == static_cast<uint8_t>(FrameType::kReady)) {
    return fail(Failure::kOutOfOrder, "a second READY");
  } else {
    return fail(Failure::kMalformed, "a frame of type " + std::to_string(type));
  }
  ++next_receive_counter_;
  ++stats_.frames_received;
  return true;
}

std::vector<uint8_t> Session::take_control() {
  if (!control_.empty()) control_taken_ = true;
  std::vector<uint8_t> c;
  c.swap(control_);
  return c;
}

std::vector<uint8_t> Session::seal(FrameType type, const std::string& channel,
                                   std::span<const uint8_t> payload) {
  auto f = seal_frame(session_key_, type, role_, next_send_counter_++, channel, payload);
  ++stats_.frames_sent;
  stats_.bytes_sent += f.size();
  return f;
}

std::vector<uint8_t> Session::seal_data(const std::string& channel,
                                        std::span<const uint8_t> payload) {
  // Programmer invariant: the node seals only on an open session, after sending its READY, with a
  // channel from its validated options and a payload it checked with fits().
  assert(open() && control_taken_ && control_.empty());
  assert(valid_channel_name(as_bytes(channel.data(), channel.size())));
  assert(fits(channel, payload.size()));
  ++stats_.data_sent;
  return seal(FrameType::kData, channel, payload);
}

std::vector<uint8_t> Session::seal_keepalive() {
  // Programmer invariant: as seal_data.
  assert(open() && control_taken_ && control_.empty());
  return seal(FrameType::kKeepalive, "", {});
}

}  // namespace alight::link
