#include "common/operator_auth.hpp"

#include <fcntl.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <openssl/rand.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cassert>
#include <cctype>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstring>

namespace alight {

namespace {

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

void put_be(std::vector<uint8_t>& out, uint64_t v, int n_bytes) {
  for (int i = n_bytes - 1; i >= 0; --i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}

}  // namespace

OperatorKey parse_key(const std::string& contents, const std::string& origin) {
  size_t begin = 0, end = contents.size();
  while (begin < end && std::isspace(static_cast<unsigned char>(contents[begin]))) ++begin;
  while (end > begin && std::isspace(static_cast<unsigned char>(contents[end - 1]))) --end;
  bool all_hex = end > begin;
  for (size_t i = begin; i < end && all_hex; ++i) all_hex = hex_value(contents[i]) >= 0;

  OperatorKey key;
  if (all_hex) {
    const size_t n_digits = end - begin;
    if (n_digits % 2 != 0)
      throw KeyFileError(origin + ": hex key has an odd number of digits (" +
                         std::to_string(n_digits) + ")");
    if (n_digits < 2 * kMinKeyBytes)
      throw KeyFileError(origin + ": key too short: " + std::to_string(n_digits / 2) +
                         " bytes in hex, need at least " + std::to_string(kMinKeyBytes) +
                         " (e.g. `openssl rand -hex 32 > KEYFILE`)");
    for (size_t i = begin; i < end; i += 2)
      key.bytes.push_back(
          static_cast<uint8_t>(16 * hex_value(contents[i]) + hex_value(contents[i + 1])));
    return key;
  }
  if (contents.size() < kMinKeyBytes)
    throw KeyFileError(origin + ": key too short: " + std::to_string(contents.size()) +
                       " bytes, need at least " + std::to_string(kMinKeyBytes) + " raw bytes or " +
                       std::to_string(2 * kMinKeyBytes) + " hex digits");
  key.bytes.assign(contents.begin(), contents.end());
  return key;
}

LoadedKey load_key_file(const std::string& path) {
  // HMAC-SHA256 hashes a key longer than its 64-byte block down to 32 bytes, so a longer file
  // adds no strength; the bound keeps a mistaken path (a log, an image) from being read whole.
  constexpr size_t kMaxKeyFileBytes = 4096;
  // stat() before open() so that a device is never opened, O_NONBLOCK so that a FIFO swapped in
  // since cannot block the open, fstat() of the opened file, which is what gets read (as
  // ParamNode::load_file; this library does not link the parameter loader).
  const auto check = [&path](const struct stat& st) {
    if (!S_ISREG(st.st_mode))
      throw KeyFileError(path +
                         ": key file is not a regular file (a FIFO or a device could "
                         "block the read or never end)");
    if (static_cast<uint64_t>(st.st_size) > kMaxKeyFileBytes)
      throw KeyFileError(path + ": key file too large: " + std::to_string(st.st_size) +
                         " bytes, at most " + std::to_string(kMaxKeyFileBytes));
  };
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw KeyFileError(path + ": key file missing or unreadable: " + std::strerror(errno));
  check(st);
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) throw KeyFileError(path + ": cannot open key file: " + std::strerror(errno));
  std::string contents(kMaxKeyFileBytes + 1, '\0');
  size_t n = 0;
  try {
    if (::fstat(fd, &st) != 0)
      throw KeyFileError(path + ": cannot stat key file: " + std::strerror(errno));
    check(st);
    while (n < contents.size()) {
      const ssize_t r = ::read(fd, contents.data() + n, contents.size() - n);
      if (r < 0 && errno == EINTR) continue;
      if (r < 0) throw KeyFileError(path + ": cannot read key file: " + std::strerror(errno));
      if (r == 0) break;
      n += static_cast<size_t>(r);
    }
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  if (n > kMaxKeyFileBytes)
    throw KeyFileError(path + ": key file too large: more than " +
                       std::to_string(kMaxKeyFileBytes) + " bytes");
  contents.resize(n);
  LoadedKey loaded;
  loaded.key = parse_key(contents, path);
  if (st.st_mode & (S_IRWXG | S_IRWXO)) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%03o", static_cast<unsigned>(st.st_mode & 0777));
    loaded.warnings.push_back(path + ": key file has mode " + mode +
                              ": other users can read or change it (chmod 600 " + path + ")");
  }
  return loaded;
}

HmacTag hmac_sha256(const uint8_t* key, size_t key_len, const uint8_t* data, size_t data_len) {
  HmacTag tag{};
  unsigned int len = 0;
  const uint8_t* out =
      HMAC(EVP_sha256(), key, static_cast<int>(key_len), data, data_len, tag.data(), &len);
  // Only fails on allocation failure or a broken OpenSSL; a zero tag must never leave here.
  if (out == nullptr || len != tag.size()) throw std::runtime_error("HMAC-SHA256 failed (OpenSSL)");
  return tag;
}

HmacTag hmac_sha256(const std::vector<uint8_t>& key, const std::vector<uint8_t>& data) {
  return hmac_sha256(key.data(), key.size(), data.data(), data.size());
}

std::vector<uint8_t> canonical_bytes(const operator_cmd_t& cmd) {
  std::vector<uint8_t> out;
  out.reserve(58 + cmd.sender.size() + cmd.vehicle_id.size() + 2);
  put_be(out, static_cast<uint64_t>(cmd.utime), 8);
  put_be(out, static_cast<uint64_t>(cmd.seq), 8);
  put_be(out, static_cast<uint32_t>(cmd.sender.size() + 1), 4);
  out.insert(out.end(), cmd.sender.begin(), cmd.sender.end());
  out.push_back(0);
  put_be(out, static_cast<uint32_t>(cmd.vehicle_id.size() + 1), 4);
  out.insert(out.end(), cmd.vehicle_id.begin(), cmd.vehicle_id.end());
  out.push_back(0);
  put_be(out, static_cast<uint64_t>(cmd.session), 8);
  out.push_back(static_cast<uint8_t>(cmd.command));
  out.push_back(static_cast<uint8_t>(cmd.mission));
  for (double d : cmd.nudge_W) {
    uint64_t bits = 0;
    static_assert(sizeof bits == sizeof d);
    std::memcpy(&bits, &d, sizeof bits);
    put_be(out, bits, 8);
  }
  return out;
}

void sign(operator_cmd_t& cmd, const OperatorKey& key) {
  assert(key.bytes.size() >= kMinKeyBytes);
  const HmacTag tag = hmac_sha256(key.bytes, canonical_bytes(cmd));
  cmd.auth = operator_cmd_t::AUTH_HMAC_SHA256;
  std::memcpy(cmd.hmac, tag.data(), tag.size());
}

bool signature_valid(const operator_cmd_t& cmd, const OperatorKey& key) {
  if (cmd.auth != operator_cmd_t::AUTH_HMAC_SHA256) return false;
  const HmacTag tag = hmac_sha256(key.bytes, canonical_bytes(cmd));
  static_assert(sizeof(cmd.hmac) == std::tuple_size_v<HmacTag>);
  // Constant time: an early-exit comparison would leak how many leading bytes of a forged tag
  // are right.
  return CRYPTO_memcmp(tag.data(), cmd.hmac, tag.size()) == 0;
}

std::string random_key_hex(size_t bytes) {
  std::vector<uint8_t> raw(bytes);
  if (RAND_bytes(raw.data(), static_cast<int>(raw.size())) != 1)
    throw std::runtime_error("RAND_bytes failed: no key");
  static const char* digits = "0123456789abcdef";
  std::string hex;
  for (uint8_t b : raw) {
    hex.push_back(digits[b >> 4]);
    hex.push_back(digits[b & 15]);
  }
  return hex + "\n";
}

int64_t draw_session_nonce() {
  for (;;) {
    uint64_t v = 0;
    if (RAND_bytes(reinterpret_cast<unsigned char*>(&v), sizeof v) != 1)
      throw std::runtime_error("RAND_bytes failed: no session nonce for the command verifier");
    v &= ~(uint64_t{1} << 63);  // positive: shown as a plain number in logs and the page
    if (v != 0) return static_cast<int64_t>(v);
  }
}

CommandVerifier::CommandVerifier(OperatorKey key, std::string vehicle_id, int64_t session,
                                 int64_t max_age_us)
    : key_(std::move(key)),
      vehicle_id_(std::move(vehicle_id)),
      session_(session),
      max_age_us_(max_age_us) {
  if (key_.bytes.size() < kMinKeyBytes)
    throw KeyFileError("CommandVerifier: key of " + std::to_string(key_.bytes.size()) +
                       " bytes, need at least " + std::to_string(kMinKeyBytes));
  // 0 is "no session" on AUTONOMY_STATUS; a verifier must never accept commands signed for it.
  if (session_ == 0) throw std::invalid_argument("CommandVerifier: session nonce 0");
  if (max_age_us_ <= 0)
    throw std::invalid_argument("CommandVerifier: max_age_us " + std::to_string(max_age_us_) +
                                " must be > 0");
}

CommandVerdict CommandVerifier::check(const operator_cmd_t& cmd, int64_t now_utime) {
  using R = CommandVerdict::Reason;
  auto reject = [&](R r) {
    ++n_rejected_;
    ++by_reason_[static_cast<size_t>(r)];
    last_rejected_seq_ = cmd.seq;
    last_reject_reason_ = r;
    return CommandVerdict{r};
  };
  if (cmd.auth != operator_cmd_t::AUTH_HMAC_SHA256) return reject(R::kUnsigned);
  if (!signature_valid(cmd, key_)) return reject(R::kBadSignature);
  if (cmd.vehicle_id != vehicle_id_) return reject(R::kWrongVehicle);
  if (cmd.session != session_) return reject(R::kWrongSession);
  // Written to avoid overflow of now - utime for adversarial utime values (they are signed, so
  // only a key holder could send them, but a buggy ground station could).
  // The differences in unsigned arithmetic are exact for any two int64 values (fuzzing found the
  // signed form overflowing near INT64_MIN).
  const auto gap = [](int64_t hi, int64_t lo) {
    return static_cast<uint64_t>(hi) - static_cast<uint64_t>(lo);
  };
  const auto max_age = static_cast<uint64_t>(max_age_us_);
  const bool too_old = cmd.utime < now_utime && gap(now_utime, cmd.utime) > max_age;
  const bool too_new = cmd.utime > now_utime && gap(cmd.utime, now_utime) > max_age;
  if (too_old || too_new) return reject(R::kStale);
  auto it = last_seq_.find(cmd.sender);
  if (it != last_seq_.end() && cmd.seq <= it->second) return reject(R::kReplayed);
  last_seq_[cmd.sender] = cmd.seq;
  return CommandVerdict{R::kNone};
}

int64_t CommandVerifier::last_seq(const std::string& sender) const {
  auto it = last_seq_.find(sender);
  return it == last_seq_.end() ? INT64_MIN : it->second;
}

const char* kill_check_name(KillCheck c) {
  switch (c) {
    case KillCheck::kAuthorised:
      return "authorised";
    case KillCheck::kNoKey:
      return "no operator key here";
    case KillCheck::kNotKill:
      return "no signed CMD_KILL attached";
    case KillCheck::kUnsigned:
      return "unsigned";
    case KillCheck::kBadSignature:
      return "bad signature";
    case KillCheck::kWrongVehicle:
      return "for another vehicle";
    case KillCheck::kStale:
      return "stale";
  }
  return "?";
}

KillVerifier::KillVerifier(std::optional<OperatorKey> key, std::string vehicle_id,
                           int64_t max_age_us)
    : key_(std::move(key)), vehicle_id_(std::move(vehicle_id)), max_age_us_(max_age_us) {}

KillCheck KillVerifier::check(const operator_cmd_t& cmd, int64_t now_utime) {
  if (!key_) return KillCheck::kNoKey;
  if (cmd.command != operator_cmd_t::CMD_KILL) return KillCheck::kNotKill;
  if (cmd.auth != operator_cmd_t::AUTH_HMAC_SHA256) return KillCheck::kUnsigned;
  if (authorised_ && authorised_->sender == cmd.sender && authorised_->seq == cmd.seq &&
      CRYPTO_memcmp(authorised_->hmac, cmd.hmac, sizeof cmd.hmac) == 0)
    return KillCheck::kAuthorised;
  if (!signature_valid(cmd, *key_)) return KillCheck::kBadSignature;
  if (cmd.vehicle_id != vehicle_id_) return KillCheck::kWrongVehicle;
  const uint64_t gap = cmd.utime < now_utime
                           ? static_cast<uint64_t>(now_utime) - static_cast<uint64_t>(cmd.utime)
                           : static_cast<uint64_t>(cmd.utime) - static_cast<uint64_t>(now_utime);
  if (gap > static_cast<uint64_t>(max_age_us_)) return KillCheck::kStale;
  authorised_ = cmd;
  return KillCheck::kAuthorised;
}

}  // namespace alight
