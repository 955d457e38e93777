#include "mocap/vrpn.hpp"

#include <cstring>

namespace alight::mocap::vrpn {

namespace {
// Keeps a peer's text printable in logs and errors.
std::string printable(const uint8_t* p, size_t n) {
  std::string s;
  for (size_t i = 0; i < n && p[i] != 0; ++i) s += (p[i] >= 0x20 && p[i] < 0x7f) ? char(p[i]) : '?';
  return s;
}

// The peer's cookie must agree with ours up to and including the last '.' of our magic.
constexpr size_t kMajorPrefix = 14;  // "vrpn: ver. 07."
}  // namespace

std::array<uint8_t, kCookieBytes> make_cookie(int remote_log_mode) {
  std::array<uint8_t, kCookieBytes> c{};
  std::memcpy(c.data(), kMagic, kMagicLength);
  c[kMagicLength] = ' ';
  c[kMagicLength + 1] = ' ';
  c[kMagicLength + 2] = static_cast<uint8_t>('0' + remote_log_mode);
  return c;
}

CookieCheck check_cookie(const uint8_t* cookie) {
  static_assert(kMajorPrefix < kMagicLength);
  CookieCheck check;
  check.version = printable(cookie + 11, kMagicLength - 11);
  if (std::memcmp(cookie, kMagic, kMajorPrefix) != 0) {
    check.verdict = CookieVerdict::kBadMagic;
    return check;
  }
  const uint8_t mode = cookie[kMagicLength + 2];
  if (mode < '0' || mode > '3') {
    check.verdict = CookieVerdict::kBadLogMode;
    return check;
  }
  check.log_mode = mode - '0';
  check.verdict = std::memcmp(cookie, kMagic, kMagicLength) == 0 ? CookieVerdict::kOk
                                                                 : CookieVerdict::kMinorDiffers;
  return check;
}

void put_u32(std::vector<uint8_t>& out, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<uint8_t>(v >> shift));
}

void put_f64(std::vector<uint8_t>& out, double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  for (int shift = 56; shift >= 0; shift -= 8) out.push_back(static_cast<uint8_t>(bits >> shift));
}

uint32_t get_u32(const uint8_t* p) {
  return uint32_t{p[0]} << 24 | uint32_t{p[1]} << 16 | uint32_t{p[2]} << 8 | uint32_t{p[3]};
}

double get_f64(const uint8_t* p) {
  const uint64_t bits = uint64_t{get_u32(p)} << 32 | get_u32(p + 4);
  double v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

void append_message(std::vector<uint8_t>& out, int32_t type, int32_t sender, uint32_t sec,
                    uint32_t usec, const uint8_t* payload, size_t size, uint32_t sequence) {
  put_u32(out, static_cast<uint32_t>(kHeaderBytes + size));
  put_u32(out, sec);
  put_u32(out, usec);
  put_u32(out, static_cast<uint32_t>(sender));
  put_u32(out, static_cast<uint32_t>(type));
  put_u32(out, sequence);
  if (size > 0) out.insert(out.end(), payload, payload + size);
  out.resize(out.size() + (padded(size) - size), 0);
}

std::vector<uint8_t> name_payload(const std::string& name) {
  std::vector<uint8_t> p;
  put_u32(p, static_cast<uint32_t>(name.size() + 1));
  p.insert(p.end(), name.begin(), name.end());
  p.push_back(0);
  return p;
}

bool StreamDecoder::fail(std::string why) {
  failed_ = true;
  error_ = std::move(why);
  buffer_.clear();
  start_ = 0;
  return false;
}

bool StreamDecoder::feed(const uint8_t* data, size_t size, std::vector<TrackerReport>& out) {
  if (failed_) return false;
  stats_.bytes += size;
  buffer_.insert(buffer_.end(), data, data + size);
  if (!cookie_received_) {
    if (pending_bytes() < kCookieBytes) return true;
    cookie_ = check_cookie(buffer_.data() + start_);
    if (!cookie_.usable()) {
      ++stats_.cookie_errors;
      return fail(cookie_.verdict == CookieVerdict::kBadLogMode
                      ? "server cookie has an invalid log mode"
                      : "not a VRPN 07 server (cookie \"" +
                            printable(buffer_.data() + start_, kMagicLength) + "\")");
    }
    cookie_received_ = true;
    start_ += kCookieBytes;
  }
  while (pending_bytes() >= kHeaderBytes) {
    const uint8_t* p = buffer_.data() + start_;
    const uint32_t length = get_u32(p);
    if (length < kHeaderBytes || length - kHeaderBytes > kMaxPayloadBytes) {
      ++stats_.framing_errors;
      return fail("message length " + std::to_string(length) + " outside [" +
                  std::to_string(kHeaderBytes) + ", " +
                  std::to_string(kHeaderBytes + kMaxPayloadBytes) + "]: stream out of step");
    }
    const size_t payload_size = length - kHeaderBytes;
    const size_t frame = kHeaderBytes + padded(payload_size);
    if (pending_bytes() < frame) break;
    ++stats_.messages;
    handle(p, payload_size, out);
    start_ += frame;
  }
  // Keeps the buffer no larger than one incomplete frame plus what the last chunk brought.
  if (start_ > 0 && (start_ == buffer_.size() || start_ >= buffer_.size() / 2)) {
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(start_));
    start_ = 0;
  }
  return true;
}

void StreamDecoder::handle(const uint8_t* p, size_t payload_size, std::vector<TrackerReport>& out) {
  const uint32_t sec = get_u32(p + 4);
  const uint32_t usec = get_u32(p + 8);
  const auto sender = static_cast<int32_t>(get_u32(p + 12));
  const auto type = static_cast<int32_t>(get_u32(p + 16));
  const uint8_t* payload = p + kHeaderBytes;
  if (type == kSenderDescription || type == kTypeDescription) {
    describe(type, sender, payload, payload_size);
    return;
  }
  if (type < 0) {
    ++stats_.system_ignored;
    return;
  }
  const auto t = types_.find(type);
  if (t == types_.end()) {
    ++stats_.undescribed;
    return;
  }
  if (t->second.kind == TypeKind::kOther) {
    ++stats_.other_messages;
    return;
  }
  const auto s = senders_.find(sender);
  if (s == senders_.end()) {
    ++stats_.undescribed;
    return;
  }
  tracker(t->second, s->second, sec, usec, payload, payload_size, out);
}

void StreamDecoder::describe(int32_t type, int32_t id, const uint8_t* payload, size_t size) {
  if (id < 0 || id >= kMaxIds || size < 4) {
    ++stats_.bad_descriptions;
    return;
  }
  const uint32_t n = get_u32(payload);  // name length including its NUL
  if (n < 2 || n > kMaxNameBytes || size != 4 + size_t{n} || payload[4 + n - 1] != 0 ||
      std::memchr(payload + 4, 0, n - 1) != nullptr) {
    ++stats_.bad_descriptions;
    return;
  }
  std::string name(reinterpret_cast<const char*>(payload + 4), n - 1);
  if (type == kSenderDescription) {
    ++stats_.sender_descriptions;
    senders_[id] = std::move(name);
    return;
  }
  ++stats_.type_descriptions;
  Type t;
  if (name == kPosQuatType)
    t.kind = TypeKind::kPose;
  else if (name == kVelocityType)
    t.kind = TypeKind::kVelocity;
  else if (name == kAccelerationType)
    t.kind = TypeKind::kAcceleration;
  t.name = std::move(name);
  types_[id] = std::move(t);
}

void StreamDecoder::tracker(const Type& type, const std::string& sender, uint32_t sec,
                            uint32_t usec, const uint8_t* payload, size_t size,
                            std::vector<TrackerReport>& out) {
  const size_t expected = type.kind == TypeKind::kPose ? kPosQuatBytes : kVelocityBytes;
  if (size != expected) {
    ++stats_.bad_payloads;
    return;
  }
  if (usec >= 1000000) {
    ++stats_.bad_stamps;
    return;
  }
  TrackerReport r;
  r.kind = type.kind == TypeKind::kPose       ? TrackerReport::Kind::kPose
           : type.kind == TypeKind::kVelocity ? TrackerReport::Kind::kVelocity
                                              : TrackerReport::Kind::kAcceleration;
  r.tracker = sender;
  r.sensor = static_cast<int32_t>(get_u32(payload));
  // Seconds as unsigned: VRPN writes a 32-bit time_t, which stays meaningful past 2038 this way.
  r.stamp_us = int64_t{sec} * 1000000 + usec;
  for (int i = 0; i < 3; ++i) r.v[i] = get_f64(payload + 8 + 8 * i);
  for (int i = 0; i < 4; ++i) r.q_xyzw[i] = get_f64(payload + 32 + 8 * i);
  if (type.kind != TypeKind::kPose) r.dt_s = get_f64(payload + 64);
  switch (r.kind) {
    case TrackerReport::Kind::kPose:
      ++stats_.poses;
      break;
    case TrackerReport::Kind::kVelocity:
      ++stats_.velocities;
      break;
    case TrackerReport::Kind::kAcceleration:
      ++stats_.accelerations;
      break;
  }
  out.push_back(std::move(r));
}

std::string StreamDecoder::type_name(int32_t id) const {
  const auto it = types_.find(id);
  return it == types_.end() ? "" : it->second.name;
}

std::string StreamDecoder::sender_name(int32_t id) const {
  const auto it = senders_.find(id);
  return it == senders_.end() ? "" : it->second;
}

}  // namespace alight::mocap::vrpn
