// MAVLink bytes from an autopilot link: alight's streaming parser over arbitrary bytes
// in arbitrary chunks, with and without a signing key, then every delivered frame decoded into its
// typed message. Input: a flags byte (bit 0: signing key, the fuzz targets' 32 bytes 0x5a; bit 1:
// accept unsigned frames too; bit 2: refuse MAVLink 1; bit 3: refuse payloads longer than known),
// a chunking seed byte, then the byte stream. Properties: every byte pushed is delivered, skipped,
// dropped or still buffered; only known messages are delivered, with a correct checksum; with a
// key, every signed frame delivered is verified and unsigned ones only when allowed; a delivered
// frame re-encoded with its header and payload gives back the bytes it was parsed from (MAVLink 2
// unsigned) and parses again to the same fields.
#include <cstdint>
#include <cstring>
#include <vector>

#include "fuzz/fuzz_support.hpp"
#include "mavlink/parser.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  using namespace alight::mavlink;
  if (size < 2) return 0;
  const uint8_t flags = data[0];
  uint32_t chunk_state = data[1] * 2654435761u + 1;
  data += 2;
  size -= 2;

  ParserOptions options;
  if (flags & 1) {
    SigningKey key;
    key.fill(0x5a);
    options.key = key;
  }
  options.accept_unsigned = flags & 2;
  options.accept_v1 = !(flags & 4);
  options.refuse_longer_than_known = flags & 8;
  Parser parser(options);
  parser.observe_time(1'767'323'045'000'000);  // 2026: old signing stamps are "too old"

  size_t pos = 0;
  Frame frame;
  while (pos < size) {
    chunk_state = chunk_state * 1103515245u + 12345u;
    const size_t n = std::min<size_t>(1 + (chunk_state >> 16) % 300, size - pos);
    parser.push({data + pos, n});
    pos += n;
    while (parser.next(frame)) {
      const MessageInfo* info = find_message(frame.msgid);
      if (info == nullptr) fuzz::fail("a frame of an unknown message was delivered");
      if (frame.version == 1 && !options.accept_v1) fuzz::fail("a MAVLink 1 frame was delivered");
      if (options.key) {
        if (frame.signature && !frame.signature_verified) fuzz::fail("unverified signed frame");
        if (!frame.signature && !options.accept_unsigned) fuzz::fail("unsigned frame delivered");
      }
      if (options.refuse_longer_than_known && frame.payload_length > info->max_length)
        fuzz::fail("a payload longer than known was delivered");
      if (!dispatch(frame, [](const auto& m) { (void)m; })) fuzz::fail("dispatch refused a frame");

      // Re-encode: same checksum, and the same frame when parsed again.
      if (frame.version == 2 && !frame.signature) {
        FrameBytes again;
        again.size = write_frame({frame.seq, frame.sysid, frame.compid, frame.compat_flags},
                                 frame.msgid, info->crc_extra, frame.payload.data(),
                                 frame.payload_length, std::nullopt, again.data.data());
        if ((again.data[again.size - 2] | (again.data[again.size - 1] << 8)) != frame.checksum)
          fuzz::fail("re-encoding gave another checksum");
        ParserOptions plain;
        Parser reparse(plain);
        reparse.push(again.bytes());
        Frame f2;
        if (!reparse.next(f2) || f2.msgid != frame.msgid || f2.payload != frame.payload ||
            f2.payload_length != frame.payload_length)
          fuzz::fail("a re-encoded frame did not parse back");
      }
    }
    const ParserStats& s = parser.stats();
    if (s.bytes_in != s.bytes_delivered + s.bytes_skipped + s.bytes_dropped + parser.buffered())
      fuzz::fail("bytes unaccounted for");
    if (parser.buffered() > 2 * kMaxFrameLength + 300)
      fuzz::fail("the parser holds more than two frames and a chunk");
  }
  return 0;
}
