// Conformance of alight's MAVLink 2 library against node-mavlink (npm, pinned in
// test/mavlink/conformance/package-lock.json; installed by scripts/setup), an implementation no
// one here wrote, in both directions and field for field:
//  (a) alight encodes every message it knows (every field distinct, extensions set; extensions
//      zero, so truncated; all fields zero; signed) -> node-mavlink splits, checks the checksum
//      with its own CRC_EXTRA, checks signatures with the key and decodes -> every header field,
//      checksum and message field compared here;
//  (b) node-mavlink encodes every message (MAVLink 2, signed, MAVLink 1, all zero) -> alight's
//      parser (with the key) delivers and decodes them -> compared with the values node-mavlink
//      was given.
// Skipped only when Node.js is absent; a missing node-mavlink is a failure that says how to
// install it.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "common/build_paths.hpp"
#include "mavlink/frame.hpp"
#include "mavlink/parser.hpp"
#include "test/mavlink/field_compare.hpp"
#include "test/mavlink/sample_messages.hpp"

namespace alight::mavlink {
namespace {

namespace fs = std::filesystem;
using testing::compare_fields;
using testing::distinct_message;
using testing::without_extensions;
using testing::zero_message;

const std::string kPeerDir = std::string(alight::build::source_dir()) + "/test/mavlink/conformance";
const std::string kNode = ALIGHT_NODE_EXECUTABLE;
constexpr int kPeerMissing = 77;

// A fixed key: bytes 0xA0, 0xA1, ... 0xBF.
SigningKey test_key() {
  SigningKey k{};
  for (size_t i = 0; i < k.size(); ++i) k[i] = static_cast<uint8_t>(0xA0 + i);
  return k;
}

std::string hex(const uint8_t* p, size_t n) {
  static const char* d = "0123456789abcdef";
  std::string s;
  for (size_t i = 0; i < n; ++i) {
    s += d[p[i] >> 4];
    s += d[p[i] & 15];
  }
  return s;
}

std::vector<uint8_t> unhex(const std::string& s) {
  std::vector<uint8_t> out;
  for (size_t i = 0; i + 1 < s.size(); i += 2)
    out.push_back(static_cast<uint8_t>(std::stoi(s.substr(i, 2), nullptr, 16)));
  return out;
}

std::string quote(const std::string& s) { return "'" + s + "'"; }

bool node_present() { return !kNode.empty() && ::access(kNode.c_str(), X_OK) == 0; }

// Runs the peer script; its stdout as JSON lines. Fails the test (and returns nothing) when the
// script does not finish with 0.
std::vector<YAML::Node> run_peer(const std::string& mode, const std::string& stdin_path = "") {
  std::string cmd = quote(kNode) + " " + quote(kPeerDir + "/mavlink_peer.mjs") + " " + mode +
                    " --key " + hex(test_key().data(), test_key().size());
  if (!stdin_path.empty()) cmd += " < " + quote(stdin_path);
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (pipe == nullptr) {
    ADD_FAILURE() << "cannot run " << cmd;
    return {};
  }
  std::string out;
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) out.append(buf, n);
  const int status = ::pclose(pipe);
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (code == kPeerMissing) {
    ADD_FAILURE() << "node-mavlink is not installed: run scripts/setup, or `cd " << kPeerDir
                  << " && npm ci` (the version is pinned in package-lock.json)";
    return {};
  }
  if (code != 0) {
    ADD_FAILURE() << cmd << " exited with " << code << "\n" << out;
    return {};
  }
  std::vector<YAML::Node> lines;
  size_t start = 0;
  while (start < out.size()) {
    size_t end = out.find('\n', start);
    if (end == std::string::npos) end = out.size();
    if (end > start) lines.push_back(YAML::Load(out.substr(start, end - start)));
    start = end + 1;
  }
  return lines;
}

uint64_t as_u64(const YAML::Node& n) { return std::stoull(n.as<std::string>()); }

// One frame alight sent, and how to check what the peer made of it.
struct Sent {
  std::string what;
  FrameBytes frame;
  bool is_signed = false;
  bool tampered = false;  // signature bytes changed after signing
  std::function<std::string(const YAML::Node&)> compare;
};

// The comparison itself: every kind of difference is reported (runs without Node.js).
TEST(MavlinkConformanceCompare, ReportsEveryKindOfDifference) {
  Statustext st;
  st.severity = 4;
  set_statustext(st, "ab\"c");
  st.id = 65535;
  EXPECT_EQ(
      compare_fields(st, YAML::Load(R"({"severity":4,"text":"ab\"c","id":65535,"chunk_seq":0})")),
      "");
  EXPECT_NE(
      compare_fields(st, YAML::Load(R"({"severity":5,"text":"ab\"c","id":65535,"chunk_seq":0})")),
      "");
  EXPECT_NE(
      compare_fields(st, YAML::Load(R"({"severity":4,"text":"ab","id":65535,"chunk_seq":0})")), "");
  EXPECT_NE(
      compare_fields(st, YAML::Load(R"({"severity":4,"text":"ab\"c","id":-1,"chunk_seq":0})")), "");
  EXPECT_NE(compare_fields(st, YAML::Load(R"({"severity":4,"text":"ab\"c","id":65535})")), "")
      << "a missing field";
  EXPECT_NE(compare_fields(
                st, YAML::Load(R"({"severity":4,"text":"ab\"c","id":65535,"chunk_seq":0,"x":1})")),
            "")
      << "a field alight does not have";

  Timesync ts;
  ts.tc1 = -9'000'000'000'000'000'000;
  ts.ts1 = 1;
  EXPECT_EQ(compare_fields(ts, YAML::Load(R"({"tc1":"-9000000000000000000","ts1":"1",)"
                                          R"("target_system":0,"target_component":0})")),
            "");
  EXPECT_NE(compare_fields(ts, YAML::Load(R"({"tc1":"-8999999999999999999","ts1":"1",)"
                                          R"("target_system":0,"target_component":0})")),
            "");

  AttPosMocap m;
  m.time_usec = 18'000'000'000'000'000'000u;
  m.q = {1.0f, 0.1f, -0.0f, 0.0f};
  m.x = std::numeric_limits<float>::quiet_NaN();
  m.y = 0.3f;
  m.z = -std::numeric_limits<float>::infinity();
  const std::string cov = R"(,"covariance":[0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0]})";
  const std::string ok =
      R"({"time_usec":"18000000000000000000","q":[1,0.10000000149011612,"-0",0],)"
      R"("x":"NaN","y":0.30000001192092896,"z":"-Infinity")";
  EXPECT_EQ(compare_fields(m, YAML::Load(ok + cov)), "");
  const std::string y_not_float =
      R"({"time_usec":"18000000000000000000","q":[1,0.10000000149011612,"-0",0],)"
      R"("x":"NaN","y":0.3,"z":"-Infinity")";
  EXPECT_EQ(compare_fields(m, YAML::Load(y_not_float + cov)), "")
      << "0.3 parsed and rounded to float is the same float";
  const std::string y_next_float =
      R"({"time_usec":"18000000000000000000","q":[1,0.10000000149011612,"-0",0],)"
      R"("x":"NaN","y":0.30000004172325134,"z":"-Infinity")";
  EXPECT_NE(compare_fields(m, YAML::Load(y_next_float + cov)), "") << "one float ulp away";
  const std::string plus_zero =
      R"({"time_usec":"18000000000000000000","q":[1,0.10000000149011612,0,0],)"
      R"("x":"NaN","y":0.30000001192092896,"z":"-Infinity")";
  EXPECT_NE(compare_fields(m, YAML::Load(plus_zero + cov)), "") << "+0 is not -0";
  const std::string short_q =
      R"({"time_usec":"18000000000000000000","q":[1,0.10000000149011612,"-0"],)"
      R"("x":"NaN","y":0.30000001192092896,"z":"-Infinity")";
  EXPECT_NE(compare_fields(m, YAML::Load(short_q + cov)), "");
}

class MavlinkConformance : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!node_present())
      GTEST_SKIP() << "Node.js not found (CMake looked for `node`; got '" << kNode
                   << "'): the node-mavlink conformance test needs it (apt-get install nodejs npm, "
                      "then scripts/setup)";
  }
};

// (a) node-mavlink decodes every message alight encodes.
TEST_F(MavlinkConformance, NodeMavlinkDecodesEveryMessageAlightEncodes) {
  // A fixed wall clock: the signed frames' timestamps are reproducible.
  const int64_t t0_unix_utime = 1'767'323'045'000'000;  // 2026-01-02 03:04:05 UTC
  Sender plain(42, mav_component::kOnboardComputer);
  Sender signer(42, mav_component::kOnboardComputer, SigningConfig{test_key(), 7});
  std::vector<Sent> sent;
  int64_t t = t0_unix_utime;
  auto add = [&](const std::string& what, const auto& m, Sender& s, bool tamper = false) {
    Sent x{std::string(m.kName) + " " + what, s.pack(m, t += 1000), s.signing(), tamper,
           [m](const YAML::Node& fields) { return compare_fields(m, fields); }};
    if (tamper) x.frame.data[x.frame.size - 1] ^= 0x01;
    sent.push_back(std::move(x));
  };
  for_each_message_type([&](auto tag) {
    using M = decltype(tag);
    add("every field set", distinct_message<M>(1), plain);
    add("extensions zero (truncated)", without_extensions(distinct_message<M>(2)), plain);
    add("all zero", zero_message<M>(), plain);
    add("signed", distinct_message<M>(3), signer);
    add("signed, signature tampered", distinct_message<M>(4), signer, true);
  });
  // Special floats: "unknown" covariances are NaN (common.xml), and a negative zero.
  AttPosMocap mocap = distinct_message<AttPosMocap>(6);
  mocap.covariance[0] = std::numeric_limits<float>::quiet_NaN();
  mocap.x = -0.0f;
  mocap.y = std::numeric_limits<float>::infinity();
  add("NaN, -0, infinity", mocap, plain);
  Odometry odom = distinct_message<Odometry>(6);
  odom.pose_covariance[0] = std::numeric_limits<float>::quiet_NaN();
  odom.velocity_covariance[0] = std::numeric_limits<float>::quiet_NaN();
  add("covariances unknown", odom, signer);
  // A frame with a wrong checksum must be refused by the peer too; it is put last.
  FrameBytes corrupt = plain.pack(distinct_message<HighresImu>(5), t);
  corrupt.data[kHeaderLengthV2 + 3] ^= 0x40;

  const fs::path input = fs::temp_directory_path() /
                         ("alight_mavlink_conformance_" + std::to_string(::getpid()) + ".bin");
  {
    std::ofstream f(input, std::ios::binary);
    for (const Sent& s : sent)
      f.write(reinterpret_cast<const char*>(s.frame.data.data()),
              static_cast<std::streamsize>(s.frame.size));
    f.write(reinterpret_cast<const char*>(corrupt.data.data()),
            static_cast<std::streamsize>(corrupt.size));
  }
  const std::vector<YAML::Node> lines = run_peer("decode", input.string());
  fs::remove(input);
  ASSERT_EQ(lines.size(), sent.size() + 1) << "one line per frame and a summary";

  for (size_t i = 0; i < sent.size(); ++i) {
    const Sent& s = sent[i];
    const YAML::Node& l = lines[i];
    SCOPED_TRACE(s.what);
    const uint8_t* b = s.frame.data.data();
    const uint8_t len = b[1];
    const uint16_t crc =
        static_cast<uint16_t>(b[kHeaderLengthV2 + len] | (b[kHeaderLengthV2 + len + 1] << 8));
    const uint32_t msgid = b[7] | (b[8] << 8) | (b[9] << 16);
    EXPECT_EQ(l["version"].as<int>(), 2);
    EXPECT_EQ(l["msgid"].as<uint32_t>(), msgid);
    EXPECT_EQ(l["len"].as<int>(), len);
    EXPECT_EQ(l["incompat_flags"].as<int>(), s.is_signed ? 1 : 0);
    EXPECT_EQ(l["compat_flags"].as<int>(), 0);
    EXPECT_EQ(l["seq"].as<int>(), b[4]);
    EXPECT_EQ(l["sysid"].as<int>(), 42);
    EXPECT_EQ(l["compid"].as<int>(), mav_component::kOnboardComputer);
    EXPECT_EQ(l["crc"].as<int>(), crc) << "checksum as received";
    EXPECT_EQ(l["crc_computed"].as<int>(), crc) << "node-mavlink's checksum with its CRC_EXTRA";
    ASSERT_EQ(l["signed"].as<bool>(), s.is_signed);
    if (s.is_signed) {
      const uint8_t* sig = b + s.frame.size - kSignatureLength;
      uint64_t ts = 0;
      for (int k = 0; k < 6; ++k) ts |= uint64_t{sig[1 + k]} << (8 * k);
      EXPECT_EQ(l["link_id"].as<int>(), 7);
      EXPECT_EQ(as_u64(l["timestamp"]), ts);
      EXPECT_EQ(l["signature_ok"].as<bool>(), !s.tampered);
    }
    EXPECT_EQ(s.compare(l["fields"]), "") << "fields node-mavlink decoded differ:";
  }
  const YAML::Node summary = lines.back()["summary"];
  ASSERT_TRUE(summary) << "no summary line";
  EXPECT_EQ(summary["valid"].as<int>(), static_cast<int>(sent.size()));
  EXPECT_GE(summary["invalid"].as<int>(), 1) << "the corrupted frame was accepted";
  EXPECT_EQ(summary["unknown"].as<int>(), 0);
}

// (b) alight decodes every frame node-mavlink encodes.
TEST_F(MavlinkConformance, AlightDecodesEveryFrameNodeMavlinkEncodes) {
  const std::vector<YAML::Node> lines = run_peer("encode");
  ASSERT_FALSE(lines.empty());
  std::vector<uint8_t> stream;
  for (const YAML::Node& l : lines) {
    const std::vector<uint8_t> bytes = unhex(l["hex"].as<std::string>());
    stream.insert(stream.end(), bytes.begin(), bytes.end());
  }
  // Known kinds: each message as MAVLink 2, signed, MAVLink 1 (ids < 256) and all zero.
  int kinds[4] = {0, 0, 0, 0};
  for (const YAML::Node& l : lines) {
    const std::string kind = l["kind"].as<std::string>();
    kinds[kind == "v2" ? 0 : kind == "v2_signed" ? 1 : kind == "v1" ? 2 : 3]++;
  }
  EXPECT_EQ(kinds[0], 23);
  EXPECT_EQ(kinds[1], 23);
  EXPECT_EQ(kinds[2], 21) << "every message but ODOMETRY (331) and SETUP_SIGNING (256) fits "
                             "MAVLink 1";
  EXPECT_EQ(kinds[3], 23);

  ParserOptions options;
  options.key = test_key();
  options.accept_unsigned = true;
  Parser parser(options);
  std::vector<Frame> frames;
  // Chunks of 1, 2, 3, 5, 8, ... bytes: frames cut everywhere.
  size_t pos = 0, a = 1, b = 2;
  while (pos < stream.size()) {
    const size_t n = std::min(a, stream.size() - pos);
    parser.push({stream.data() + pos, n});
    pos += n;
    Frame f;
    while (parser.next(f)) frames.push_back(f);
    const size_t c = a + b;
    a = b;
    b = c > 89 ? 1 : c;
  }
  const ParserStats& st = parser.stats();
  EXPECT_EQ(st.crc_errors, 0u);
  EXPECT_EQ(st.unknown_ids, 0u);
  EXPECT_EQ(st.signature_failures, 0u);
  EXPECT_EQ(st.replays, 0u);
  EXPECT_EQ(st.bad_length, 0u);
  EXPECT_EQ(st.bytes_dropped, 0u);
  EXPECT_EQ(st.bytes_delivered, stream.size());
  ASSERT_EQ(frames.size(), lines.size());

  for (size_t i = 0; i < lines.size(); ++i) {
    const YAML::Node& l = lines[i];
    const Frame& f = frames[i];
    const std::string kind = l["kind"].as<std::string>();
    SCOPED_TRACE(l["name"].as<std::string>() + " " + kind);
    EXPECT_TRUE(l["roundtrip_ok"].as<bool>()) << "node-mavlink disagrees with itself";
    EXPECT_EQ(f.version, kind == "v1" ? 1 : 2);
    EXPECT_EQ(f.msgid, l["msgid"].as<uint32_t>());
    EXPECT_EQ(f.seq, l["seq"].as<int>());
    EXPECT_EQ(f.sysid, 1);
    EXPECT_EQ(f.compid, 1);
    if (kind == "v2_signed") {
      ASSERT_TRUE(f.signature.has_value());
      EXPECT_TRUE(f.signature_verified);
      EXPECT_EQ(f.signature->link_id, l["link_id"].as<int>());
      EXPECT_EQ(f.signature->timestamp, as_u64(l["timestamp"]));
    } else {
      EXPECT_FALSE(f.signature.has_value());
    }
    if (kind == "v2_zero") {
      // node-mavlink truncates an all-zero payload to nothing; the protocol keeps one byte, and
      // asks receivers to accept what it gets.
      EXPECT_LE(f.payload_length, 1);
    }
    std::string diff;
    const bool known = dispatch(f, [&](const auto& m) { diff = compare_fields(m, l["fields"]); });
    ASSERT_TRUE(known);
    EXPECT_EQ(diff, "") << "fields alight decoded differ from those node-mavlink was given:";
  }
}

}  // namespace
}  // namespace alight::mavlink
