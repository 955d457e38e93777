#include "mavlink/parser.hpp"

#include <cstring>

#include "mavlink/crc.hpp"

namespace alight::mavlink {

namespace {

uint16_t get_u16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }

bool is_stx(uint8_t b) { return b == kStxV2 || b == kStxV1; }

uint16_t frame_crc(const uint8_t* p, size_t header_length, size_t payload_length,
                   uint8_t crc_extra) {
  return crc_accumulate(crc_extra,
                        crc_accumulate(p + 1, header_length - 1 + payload_length, kCrcInit));
}

}  // namespace

Parser::Parser(ParserOptions options) : options_(options) { buf_.reserve(2 * kMaxFrameLength); }

void Parser::push(std::span<const uint8_t> bytes) {
  if (head_ > 0) {
    buf_.erase(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(head_));
    head_ = 0;
  }
  buf_.insert(buf_.end(), bytes.begin(), bytes.end());
  stats_.bytes_in += bytes.size();
}

void Parser::observe_time(int64_t now_unix_utime) {
  streams_.observe(signing_timestamp_from_unix_utime(now_unix_utime));
}

void Parser::clear() { drop(buffered()); }

void Parser::drop(size_t n) {
  head_ += n;
  stats_.bytes_dropped += n;
}

void Parser::skip(size_t n) {
  head_ += n;
  stats_.bytes_skipped += n;
}

bool Parser::next(Frame& out) {
  for (;;) {
    const size_t avail = buffered();
    if (avail == 0) return false;
    const uint8_t* p = buf_.data() + head_;
    if (!is_stx(p[0])) {
      size_t n = 1;
      while (n < avail && !is_stx(p[n])) ++n;
      drop(n);
      continue;
    }
    const Step step = p[0] == kStxV2 ? parse_v2(p, avail, out) : parse_v1(p, avail, out);
    if (step == Step::kNeedMore) return false;
    if (step == Step::kDelivered) return true;
  }
}

Parser::Probe Parser::probe_known_frame(const uint8_t* p, size_t avail) const {
  size_t header_length = 0, length = 0;
  uint32_t msgid = 0;
  bool is_signed = false;
  if (p[0] == kStxV2) {
    if (avail < kHeaderLengthV2) return Probe::kNeedMore;
    if (p[2] & ~kIncompatSigned) return Probe::kNo;
    header_length = kHeaderLengthV2;
    length = p[1];
    is_signed = p[2] & kIncompatSigned;
    msgid = p[7] | (uint32_t{p[8]} << 8) | (uint32_t{p[9]} << 16);
  } else if (p[0] == kStxV1 && options_.accept_v1) {
    if (avail < kHeaderLengthV1) return Probe::kNeedMore;
    header_length = kHeaderLengthV1;
    length = p[1];
    msgid = p[5];
  } else {
    return Probe::kNo;
  }
  const MessageInfo* info = find_message(msgid);
  if (info == nullptr) return Probe::kNo;
  const size_t total =
      header_length + length + kChecksumLength + (is_signed ? kSignatureLength : 0);
  if (avail < total) return Probe::kNeedMore;
  return frame_crc(p, header_length, length, info->crc_extra) == get_u16(p + header_length + length)
             ? Probe::kYes
             : Probe::kNo;
}

Parser::Step Parser::undecided(const uint8_t* p, size_t avail) {
  // The candidate at p cannot be judged with the bytes buffered so far. A real frame still
  // arriving holds only its own bytes after its start marker; a complete, correctly checksummed
  // frame of a known message after it therefore means the marker was noise (a length byte that
  // claims more than came). Otherwise wait. Start markers already judged "no" are not probed
  // again while the same candidate waits.
  const uint64_t consumed = stats_.bytes_in - buffered();
  size_t i = (scan_consumed_ == consumed && scan_from_ > 1) ? scan_from_ : 1;
  size_t first_open = avail;
  for (; i < avail; ++i) {
    if (!is_stx(p[i])) continue;
    const Probe r = probe_known_frame(p + i, avail - i);
    if (r == Probe::kYes) {
      drop(1);
      return Step::kContinue;
    }
    if (r == Probe::kNeedMore && first_open == avail) first_open = i;
  }
  scan_consumed_ = consumed;
  scan_from_ = first_open;
  return Step::kNeedMore;
}

Parser::Step Parser::skip_uncheckable(const uint8_t* p, size_t avail, size_t total,
                                      uint64_t& counter) {
  // Without the message's CRC_EXTRA nothing proves the length byte, and a noise byte that looks
  // like a start marker could swallow up to 280 bytes of real frames. So the frame is noise when
  // a checkable frame lies inside it, and is skipped whole only when a checkable frame starts
  // right after it, or another start marker does and nothing inside is still undecided.
  if (avail < total + 1) return undecided(p, avail);
  bool open = false;
  for (size_t i = 1; i < total; ++i) {
    if (!is_stx(p[i])) continue;
    const Probe r = probe_known_frame(p + i, avail - i);
    if (r == Probe::kYes) {
      drop(1);
      return Step::kContinue;
    }
    open = open || r == Probe::kNeedMore;
  }
  switch (probe_known_frame(p + total, avail - total)) {
    case Probe::kYes:
      ++counter;
      skip(total);
      return Step::kContinue;
    case Probe::kNeedMore:
      return undecided(p, avail);
    case Probe::kNo:
      break;
  }
  if (!is_stx(p[total])) {
    drop(1);
    return Step::kContinue;
  }
  if (open) return undecided(p, avail);
  ++counter;
  skip(total);
  return Step::kContinue;
}

bool Parser::signing_allows(const uint8_t* p, size_t total, bool is_signed, Frame& out) {
  out.signature.reset();
  out.signature_verified = false;
  if (is_signed) {
    const uint8_t* s = p + total - kSignatureLength;
    Signature sig;
    sig.link_id = s[0];
    for (int i = 0; i < 6; ++i) sig.timestamp |= static_cast<uint64_t>(s[1 + i]) << (8 * i);
    std::memcpy(sig.value.data(), s + 7, sig.value.size());
    if (options_.key) {
      if (!signature_matches(*options_.key, p, total - sig.value.size(), sig.value.data())) {
        ++stats_.signature_failures;
        return false;
      }
      if (streams_.accept(p[5], p[6], sig.link_id, sig.timestamp) !=
          SignedStreams::Verdict::kAccepted) {
        ++stats_.replays;
        return false;
      }
      out.signature_verified = true;
    } else {
      ++stats_.signed_unverified;
    }
    out.signature = sig;
  } else if (options_.key && !options_.accept_unsigned) {
    ++stats_.unsigned_refused;
    return false;
  }
  return true;
}

Parser::Step Parser::parse_v2(const uint8_t* p, size_t avail, Frame& out) {
  if (avail < kHeaderLengthV2) return Step::kNeedMore;
  const uint8_t len = p[1];
  const uint8_t incompat = p[2];
  if (incompat & ~kIncompatSigned) {
    // The flag may change the frame's layout, so not even its length is known.
    ++stats_.incompat_flags;
    drop(1);
    return Step::kContinue;
  }
  const bool is_signed = incompat & kIncompatSigned;
  const size_t total = kHeaderLengthV2 + len + kChecksumLength + (is_signed ? kSignatureLength : 0);
  const uint32_t msgid = p[7] | (uint32_t{p[8]} << 8) | (uint32_t{p[9]} << 16);
  const MessageInfo* info = find_message(msgid);
  if (info == nullptr) return skip_uncheckable(p, avail, total, stats_.unknown_ids);
  if (avail < total) return undecided(p, avail);

  const uint16_t crc = frame_crc(p, kHeaderLengthV2, len, info->crc_extra);
  if (crc != get_u16(p + kHeaderLengthV2 + len)) {
    ++stats_.crc_errors;
    drop(1);
    return Step::kContinue;
  }
  if (len > info->max_length) {
    ++stats_.longer_than_known;
    if (options_.refuse_longer_than_known) {
      skip(total);
      return Step::kContinue;
    }
  }
  if (!signing_allows(p, total, is_signed, out)) {
    skip(total);
    return Step::kContinue;
  }
  out.version = 2;
  out.incompat_flags = incompat;
  out.compat_flags = p[3];
  out.seq = p[4];
  out.sysid = p[5];
  out.compid = p[6];
  out.msgid = msgid;
  out.payload_length = len;
  std::memcpy(out.payload.data(), p + kHeaderLengthV2, len);
  std::memset(out.payload.data() + len, 0, out.payload.size() - len);
  out.checksum = crc;
  head_ += total;
  stats_.bytes_delivered += total;
  ++stats_.frames_ok;
  return Step::kDelivered;
}

Parser::Step Parser::parse_v1(const uint8_t* p, size_t avail, Frame& out) {
  if (avail < kHeaderLengthV1) return Step::kNeedMore;
  const uint8_t len = p[1];
  const size_t total = kHeaderLengthV1 + len + kChecksumLength;
  const uint8_t msgid = p[5];
  const MessageInfo* info = find_message(msgid);
  if (!options_.accept_v1) return skip_uncheckable(p, avail, total, stats_.v1_skipped);
  if (info == nullptr) return skip_uncheckable(p, avail, total, stats_.unknown_ids);
  if (avail < total) return undecided(p, avail);

  const uint16_t crc = frame_crc(p, kHeaderLengthV1, len, info->crc_extra);
  if (crc != get_u16(p + kHeaderLengthV1 + len)) {
    ++stats_.crc_errors;
    drop(1);
    return Step::kContinue;
  }
  // MAVLink 1 never truncates: a shorter payload is another definition of the message. Longer
  // ones carry extension fields (some MAVLink 2 libraries send them in MAVLink 1 frames too).
  if (len < info->base_length) {
    ++stats_.bad_length;
    skip(total);
    return Step::kContinue;
  }
  if (len > info->max_length) {
    ++stats_.longer_than_known;
    if (options_.refuse_longer_than_known) {
      skip(total);
      return Step::kContinue;
    }
  }
  if (!signing_allows(p, total, false, out)) {
    skip(total);
    return Step::kContinue;
  }
  out.version = 1;
  out.incompat_flags = 0;
  out.compat_flags = 0;
  out.seq = p[2];
  out.sysid = p[3];
  out.compid = p[4];
  out.msgid = msgid;
  out.payload_length = len;
  std::memcpy(out.payload.data(), p + kHeaderLengthV1, len);
  std::memset(out.payload.data() + len, 0, out.payload.size() - len);
  out.checksum = crc;
  head_ += total;
  stats_.bytes_delivered += total;
  ++stats_.frames_ok;
  ++stats_.frames_v1;
  return Step::kDelivered;
}

}  // namespace alight::mavlink
