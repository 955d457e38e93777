#include "mavlink/signing.hpp"

#include <openssl/crypto.h>
#include <openssl/sha.h>

#include <cassert>
#include <cctype>
#include <cstring>

namespace alight::mavlink {

uint64_t signing_timestamp_from_unix_utime(int64_t unix_utime) {
  if (unix_utime <= kSigningEpochUnixUtime) return 0;
  const uint64_t ts = static_cast<uint64_t>(unix_utime - kSigningEpochUnixUtime) / 10;
  return ts > kMaxSigningTimestamp ? kMaxSigningTimestamp : ts;
}

SigningKey signing_key_from_passphrase(std::string_view passphrase) {
  SigningKey key{};
  SHA256(reinterpret_cast<const unsigned char*>(passphrase.data()), passphrase.size(), key.data());
  return key;
}

std::optional<SigningKey> signing_key_from_hex(std::string_view hex) {
  while (!hex.empty() && std::isspace(static_cast<unsigned char>(hex.front())))
    hex.remove_prefix(1);
  while (!hex.empty() && std::isspace(static_cast<unsigned char>(hex.back()))) hex.remove_suffix(1);
  if (hex.size() != 64) return std::nullopt;
  auto nibble = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  };
  SigningKey key{};
  for (size_t i = 0; i < key.size(); ++i) {
    const int hi = nibble(hex[2 * i]), lo = nibble(hex[2 * i + 1]);
    if (hi < 0 || lo < 0) return std::nullopt;
    key[i] = static_cast<uint8_t>(16 * hi + lo);
  }
  return key;
}

std::array<uint8_t, 6> compute_signature(const SigningKey& key, const uint8_t* frame, size_t n) {
  // Key and frame in one buffer for the one-shot SHA256() (OpenSSL 3 deprecates the incremental
  // SHA256_* calls; EVP would allocate a context per frame).
  constexpr size_t kMaxSigned = 10 + 255 + 2 + 7;
  assert(n <= kMaxSigned);
  std::array<uint8_t, 32 + kMaxSigned> buf;
  std::memcpy(buf.data(), key.data(), key.size());
  std::memcpy(buf.data() + key.size(), frame, n);
  std::array<uint8_t, SHA256_DIGEST_LENGTH> digest{};
  SHA256(buf.data(), key.size() + n, digest.data());
  std::array<uint8_t, 6> out{};
  std::memcpy(out.data(), digest.data(), out.size());
  return out;
}

bool signature_matches(const SigningKey& key, const uint8_t* frame, size_t n,
                       const uint8_t* value) {
  const auto expected = compute_signature(key, frame, n);
  return CRYPTO_memcmp(expected.data(), value, expected.size()) == 0;
}

SignedStreams::Verdict SignedStreams::accept(uint8_t sysid, uint8_t compid, uint8_t link_id,
                                             uint64_t timestamp) {
  const uint32_t stream = (uint32_t{sysid} << 16) | (uint32_t{compid} << 8) | link_id;
  const auto it = last_.find(stream);
  if (it != last_.end()) {
    if (timestamp <= it->second) return Verdict::kReplay;
    it->second = timestamp;
  } else {
    if (timestamp + kNewStreamMaxLag < local_timestamp_) return Verdict::kTooOld;
    last_.emplace(stream, timestamp);
  }
  observe(timestamp);
  return Verdict::kAccepted;
}

}  // namespace alight::mavlink
