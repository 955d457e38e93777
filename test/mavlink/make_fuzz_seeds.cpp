// Writes the committed seeds of the mavlink_parser fuzz target (fuzz/mavlink_parser.cpp):
//   build/bin/tests/mavlink_fuzz_seeds fuzz/corpus/mavlink_parser
// Each seed is a flags byte, a chunking byte, then a byte stream of real frames: every known
// message unsigned, signed with the fuzz key (32 bytes 0x5a), MAVLink 1, all zero, unknown
// messages, noise between frames, payloads longer than known.

#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "mavlink/frame.hpp"
#include "test/mavlink/sample_messages.hpp"

using namespace alight::mavlink;
using Bytes = std::vector<uint8_t>;

namespace {

void append(Bytes& out, const FrameBytes& f) {
  out.insert(out.end(), f.data.begin(), f.data.begin() + f.size);
}

bool write(const std::string& dir, const std::string& name, uint8_t flags, const Bytes& stream) {
  std::ofstream f(dir + "/" + name, std::ios::binary);
  const uint8_t head[2] = {flags, 7};
  f.write(reinterpret_cast<const char*>(head), 2);
  f.write(reinterpret_cast<const char*>(stream.data()),
          static_cast<std::streamsize>(stream.size()));
  if (!f) std::fprintf(stderr, "cannot write %s/%s\n", dir.c_str(), name.c_str());
  return static_cast<bool>(f);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUTDIR\n", argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  SigningKey fuzz_key;
  fuzz_key.fill(0x5a);
  const int64_t t = 1'767'323'046'000'000;  // just after the fuzz target's receiver clock

  Bytes all, signed_all, mixed, v1, zeros, noisy, unknown, longer;
  Sender plain(1, 1), signer(1, 1, SigningConfig{fuzz_key, 2});
  std::mt19937 rng(5);
  int k = 0;
  for_each_message_type([&](auto tag) {
    using M = decltype(tag);
    const M m = testing::distinct_message<M>(1);
    append(all, plain.pack(m, 0));
    append(signed_all, signer.pack(m, t + 1000 * k));
    append(mixed, (k % 2 ? signer.pack(m, t + 1000 * k) : plain.pack(m, 0)));
    append(zeros, plain.pack(testing::zero_message<M>(), 0));
    if (M::kId < 256) {
      std::array<uint8_t, M::kMaxLength> payload;
      encode_payload(m, payload.data());
      std::array<uint8_t, kMaxFrameLength> out;
      const size_t n =
          write_frame_v1({static_cast<uint8_t>(k), 1, 1, 0}, static_cast<uint8_t>(M::kId),
                         M::kCrcExtra, payload.data(), M::kBaseLength, out.data());
      v1.insert(v1.end(), out.begin(), out.begin() + n);
    }
    for (int i = 0; i < 12; ++i) noisy.push_back(i % 4 == 0 ? kStxV2 : static_cast<uint8_t>(rng()));
    append(noisy, plain.pack(m, 0));
    const uint8_t junk[40] = {3, kStxV1, 9, 0, 0, 0, 0, kStxV2, 1, 2};
    append(unknown, plain.pack_payload(1000 + k, 0, junk, 40, 0));
    append(unknown, plain.pack(m, 0));
    std::array<uint8_t, 255> big{};
    encode_payload(m, big.data());
    big[M::kMaxLength] = 0x99;
    append(longer, plain.pack_payload(M::kId, M::kCrcExtra, big.data(),
                                      static_cast<uint8_t>(M::kMaxLength + 1), 0));
    ++k;
  });
  const bool ok =
      write(dir, "all_messages", 0, all) && write(dir, "signed", 1, signed_all) &&
      write(dir, "signed_and_unsigned", 3, mixed) && write(dir, "mavlink1", 0, v1) &&
      write(dir, "all_zero", 0, zeros) && write(dir, "noise_between_frames", 0, noisy) &&
      write(dir, "unknown_messages", 0, unknown) && write(dir, "longer_than_known", 8, longer);
  return ok ? 0 : 1;
}
