#include "common/node.hpp"

#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <alight/imu_t.hpp>
#include <alight/node_status_t.hpp>
#include <alight/operator_cmd_t.hpp>
#include <alight/pose_t.hpp>
#include <chrono>
#include <csignal>
#include <thread>

namespace alight {
namespace {

// A private port per test binary so tests running in parallel never hear each other.
constexpr const char* kUrl = "udpm://239.255.76.67:7711?ttl=0";

// Spins until `done` or the deadline (LCM delivers asynchronously through the kernel).
template <class Pred>
bool spin_until(Node& node, Pred done, double timeout_s = 3.0) {
  const int64_t end = wall_utime() + static_cast<int64_t>(timeout_s * 1e6);
  while (!done() && wall_utime() < end) node.spin_once(20);
  return done();
}

imu_t imu(int64_t seq) {
  imu_t m{};
  m.utime = 1000 + seq;
  m.seq = seq;
  return m;
}

TEST(NodeTest, ReceiveBufferIsAddedToUdpmUrlsOnly) {
  EXPECT_EQ(with_receive_buffer("udpm://239.255.76.67:7667?ttl=0", 1000),
            "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=1000");
  EXPECT_EQ(with_receive_buffer("udpm://239.255.76.67:7667", 1000),
            "udpm://239.255.76.67:7667?recv_buf_size=1000");
  EXPECT_EQ(with_receive_buffer("udpm://x:1?recv_buf_size=5", 1000), "udpm://x:1?recv_buf_size=5");
  EXPECT_EQ(with_receive_buffer("file:///tmp/a.lcmlog?mode=r", 1000),
            "file:///tmp/a.lcmlog?mode=r");
}

TEST(NodeTest, OnDeliversEveryMessageInOrder) {
  Node pub(kUrl, "pub"), sub(kUrl, "sub");
  std::vector<int64_t> seen;
  sub.on<imu_t>("NODE_TEST_ALL", [&](const imu_t& m) { seen.push_back(m.seq); });
  // A burst larger than LCM 1.3.1's default 30-message queue, published before any handling.
  for (int i = 0; i < 500; ++i) pub.publish("NODE_TEST_ALL", imu(i));
  ASSERT_TRUE(spin_until(sub, [&] { return seen.size() >= 500; })) << seen.size();
  for (int i = 0; i < 500; ++i) EXPECT_EQ(seen[i], i);
  EXPECT_EQ(sub.stats("NODE_TEST_ALL").received, 500u);
}

// The vision pairs frames with poses by their arrival order: on() keeps it across channels.
TEST(NodeTest, OnKeepsTheArrivalOrderAcrossChannels) {
  Node pub(kUrl, "pub"), sub(kUrl, "sub");
  std::vector<std::string> seen;
  sub.on<imu_t>("NODE_TEST_ORDER_A",
                [&](const imu_t& m) { seen.push_back("A" + std::to_string(m.seq)); });
  sub.on<imu_t>("NODE_TEST_ORDER_B",
                [&](const imu_t& m) { seen.push_back("B" + std::to_string(m.seq)); });
  std::vector<std::string> sent;
  for (int i = 0; i < 300; ++i) {
    const bool a = (i * 7) % 3 != 0;
    pub.publish(a ? "NODE_TEST_ORDER_A" : "NODE_TEST_ORDER_B", imu(i));
    sent.push_back((a ? "A" : "B") + std::to_string(i));
  }
  ASSERT_TRUE(spin_until(sub, [&] { return seen.size() >= sent.size(); })) << seen.size();
  EXPECT_EQ(seen, sent);
}

// Issue 15: a handler slower than its input holds at most `capacity` messages of that channel;
// the newest beyond it are dropped unread and counted, never silently.
TEST(NodeTest, AFullQueueDropsTheNewestAndCountsThem) {
  Node pub(kUrl, "pub"), sub(kUrl, "bounded");
  std::vector<int64_t> seen;
  Receipt first{};
  const int64_t before = wall_utime();
  sub.on<imu_t>(
      "NODE_TEST_BOUNDED",
      [&](const imu_t& m) {
        if (seen.empty()) first = sub.receipt();
        seen.push_back(m.seq);
      },
      50);
  for (int i = 0; i < 200; ++i) pub.publish("NODE_TEST_BOUNDED", imu(i));
  // Everything arrives before the first spin reads it: 50 fit, the rest are dropped.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const auto& st = sub.stats("NODE_TEST_BOUNDED");
  ASSERT_TRUE(spin_until(sub, [&] { return seen.size() + st.dropped >= 200; }))
      << seen.size() << " + " << st.dropped;
  EXPECT_EQ(seen.size() + st.dropped, 200u);
  EXPECT_GT(st.dropped, 0u);
  EXPECT_EQ(st.received, seen.size());
  // Nothing waiting is dropped: the first 50 always arrive, and every one in order, once.
  ASSERT_GE(seen.size(), 50u);
  for (size_t i = 0; i < seen.size(); ++i) {
    if (i < 50) {
      EXPECT_EQ(seen[i], static_cast<int64_t>(i));
    }
    if (i > 0) {
      EXPECT_GT(seen[i], seen[i - 1]);
    }
  }
  const node_status_t status = sub.status_message(1);
  ASSERT_EQ(status.n, 1);
  EXPECT_EQ(status.channels.at(0).dropped, static_cast<int64_t>(st.dropped));
  // The receipt is when the node read the message, for the handler's timing.
  EXPECT_GE(first.wall_utime, before);
  EXPECT_LE(first.wall_utime, wall_utime());
  EXPECT_GT(first.steady_utime, 0);
}

TEST(NodeTest, OnLatestCallsBackWithTheNewestAndCountsSkipped) {
  Node pub(kUrl, "pub"), sub(kUrl, "sub");
  std::vector<int64_t> seen;
  sub.on_latest<imu_t>("NODE_TEST_LATEST", [&](const imu_t& m) { seen.push_back(m.seq); });
  for (int i = 0; i < 50; ++i) pub.publish("NODE_TEST_LATEST", imu(i));
  // Let everything arrive in the socket, then handle it all in one spin.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  ASSERT_TRUE(spin_until(sub, [&] { return !seen.empty() && seen.back() == 49; }));
  EXPECT_LT(seen.size(), 50u);  // older ones were replaced, not queued
  EXPECT_EQ(sub.stats("NODE_TEST_LATEST").received, seen.size());
  EXPECT_EQ(sub.stats("NODE_TEST_LATEST").skipped + seen.size(), 50u);
}

TEST(NodeTest, MalformedMessagesAreCountedNotDelivered) {
  Node pub(kUrl, "pub"), sub(kUrl, "sub");
  int delivered = 0;
  sub.on<pose_t>("NODE_TEST_BAD", [&](const pose_t&) { ++delivered; });
  const std::vector<uint8_t> junk(37, 0xAB);  // wrong fingerprint and length
  // Through publish_raw: from the same publisher as the rest (another would be refused earlier).
  pub.publish_raw("NODE_TEST_BAD", junk);
  pub.publish("NODE_TEST_BAD", imu(1));  // a valid message of another type
  pose_t good{};
  good.orientation[0] = 1;
  pub.publish("NODE_TEST_BAD", good);
  ASSERT_TRUE(spin_until(
      sub, [&] { return delivered == 1 && sub.stats("NODE_TEST_BAD").decode_errors == 2; }));
  EXPECT_EQ(sub.stats("NODE_TEST_BAD").received, 1u);
}

// Regression (issue 14): one 28-byte OPERATOR_CMD (right fingerprint, a string length of 0)
// made lcm-gen's decoder throw std::length_error out of Node::decode and alight-autonomy exited.
TEST(NodeTest, RegressionZeroLengthStringIsADecodeErrorNotAnException) {
  Node pub(kUrl, "pub"), sub(kUrl, "sub");
  int delivered = 0;
  sub.on<operator_cmd_t>("NODE_TEST_CMD", [&](const operator_cmd_t&) { ++delivered; });
  operator_cmd_t c{};
  c.sender = "gs";
  std::vector<uint8_t> bytes(c.getEncodedSize());
  c.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  bytes.resize(28);
  for (int i = 0; i < 4; ++i) bytes[24 + i] = 0;  // the sender string's length
  pub.publish_raw("NODE_TEST_CMD", bytes);
  pub.publish("NODE_TEST_CMD", c);
  ASSERT_TRUE(spin_until(
      sub, [&] { return delivered == 1 && sub.stats("NODE_TEST_CMD").decode_errors == 1; }));
}

TEST(NodeTest, RefusedValuesAndStampsAreCountedAndReported) {
  Node node(kUrl, "counted");
  node.on<imu_t>("NODE_TEST_COUNT", [](const imu_t&) {});
  EXPECT_FALSE(node.reject_value("NODE_TEST_COUNT", "accel not finite"));
  EXPECT_TRUE(node.accept_stamp("NODE_TEST_COUNT", wall_utime()));
  EXPECT_FALSE(node.accept_stamp("NODE_TEST_COUNT", wall_utime() + 3'600'000'000LL));
  EXPECT_FALSE(node.accept_stamp("NODE_TEST_COUNT", 0));
  EXPECT_EQ(node.stats("NODE_TEST_COUNT").rejected_values, 1u);
  EXPECT_EQ(node.stats("NODE_TEST_COUNT").rejected_stamps, 2u);
  const node_status_t st = node.status_message(123);
  EXPECT_EQ(st.node, "counted");
  EXPECT_EQ(st.utime, 123);
  ASSERT_EQ(st.n, 1);
  EXPECT_EQ(st.channels.at(0).channel, "NODE_TEST_COUNT");
  EXPECT_EQ(st.channels.at(0).rejected_values, 1);
  EXPECT_EQ(st.channels.at(0).rejected_stamps, 2);
}

// A signed bus (--bus-key): unsigned and wrongly signed messages are refused on arrival and
// counted; the signed ones pass.
TEST(NodeTest, ASignedNodeRefusesWhatIsNotSignedWithItsKey) {
  const bus::BusKey key = bus::make_bus_key(std::vector<uint8_t>(32, 0x5a));
  const bus::BusKey other = bus::make_bus_key(std::vector<uint8_t>(32, 0xa5));
  Node sub(kUrl, "sub", key), signed_pub(kUrl, "signed", key);
  std::vector<int64_t> seen;
  sub.on<imu_t>("NODE_TEST_SIGNED", [&](const imu_t& m) { seen.push_back(m.seq); });
  {
    Node plain(kUrl, "plain"), wrong(kUrl, "wrong", other);
    plain.publish("NODE_TEST_SIGNED", imu(1));
    wrong.publish("NODE_TEST_SIGNED", imu(2));
    ASSERT_TRUE(spin_until(sub, [&] { return sub.stats("NODE_TEST_SIGNED").rejected_auth == 2; }));
  }
  signed_pub.publish("NODE_TEST_SIGNED", imu(3));
  ASSERT_TRUE(spin_until(sub, [&] { return seen.size() == 1; }));
  EXPECT_EQ(seen[0], 3);
  EXPECT_TRUE(signed_pub.signing());
  const node_status_t st = sub.status_message(wall_utime());
  EXPECT_TRUE(st.signed_bus);
  EXPECT_EQ(st.source, static_cast<int64_t>(sub.source_id()));
  bool found = false;
  for (const auto& c : st.channels)
    if (c.channel == "NODE_TEST_SIGNED") {
      found = true;
      EXPECT_EQ(c.rejected_auth, 2);
      EXPECT_EQ(c.received, 1);
    }
  EXPECT_TRUE(found);
}

// Regression: a forged message stamped 0.45 s ahead was accepted and the true publisher's next
// messages were then refused as "backwards". Now the forger is a second publisher, refused on
// arrival, and the stamp guard judges each publisher on its own.
TEST(NodeTest, ASecondPublisherCannotCaptureAChannelOrItsStamps) {
  Node genuine(kUrl, "genuine"), forger(kUrl, "forger"), sub(kUrl, "sub");
  std::vector<int64_t> used;
  sub.on<imu_t>("NODE_TEST_SECOND", [&](const imu_t& m) {
    if (sub.accept_stamp("NODE_TEST_SECOND", m.utime)) used.push_back(m.seq);
  });
  const int64_t t0 = wall_utime();
  auto sample = [&](int64_t seq, int64_t utime) {
    imu_t m = imu(seq);
    m.utime = utime;
    return m;
  };
  genuine.publish("NODE_TEST_SECOND", sample(1, t0));
  ASSERT_TRUE(spin_until(sub, [&] { return used.size() == 1; }));
  forger.publish("NODE_TEST_SECOND", sample(99, t0 + 450'000));
  ASSERT_TRUE(spin_until(sub, [&] { return sub.stats("NODE_TEST_SECOND").second_publisher == 1; }));
  EXPECT_TRUE(sub.contested("NODE_TEST_SECOND"));
  genuine.publish("NODE_TEST_SECOND", sample(2, t0 + 10'000));
  ASSERT_TRUE(spin_until(sub, [&] { return used.size() == 2; }));
  EXPECT_EQ(used, (std::vector<int64_t>{1, 2}));
  EXPECT_EQ(sub.stats("NODE_TEST_SECOND").rejected_stamps, 0u);
}

// A signed node that subscribes to nothing (a camera) still stamps its counters no lower than the
// bus time it hears on NODE_STATUS: after a boot without a real-time clock its own wall clock is
// decades behind, and signed peers would take its messages for an old recording.
TEST(NodeTest, ASignedNodeWithoutSubscriptionsLearnsTheBusTime) {
  const bus::BusKey key = bus::make_bus_key(std::vector<uint8_t>(32, 0x77));
  Node quiet(kUrl, "quiet", key), ahead(kUrl, "ahead", key), listener(kUrl, "listener", key);
  struct Counters {
    std::vector<uint64_t> seen;
    void on(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      const auto r = bus::split(rbuf->data, rbuf->data_size);
      if (r.trailer) seen.push_back(r.trailer->counter);
    }
  } counters;
  listener.lcm().subscribe("NODE_TEST_BUS_TIME", &Counters::on, &counters);
  quiet.spin_once(0);  // adds its NODE_STATUS listener
  // A peer whose clock is an hour ahead publishes its status.
  node_status_t st{};
  st.node = "ahead";
  std::vector<uint8_t> status(static_cast<size_t>(st.getEncodedSize()));
  st.encode(status.data(), 0, static_cast<int>(status.size()));
  bus::Sealer far(99, key);
  far.seal(status, channels::kNodeStatus, wall_utime() + 3'600'000'000LL);
  ahead.lcm().publish(channels::kNodeStatus, status.data(), static_cast<unsigned>(status.size()));
  ASSERT_TRUE(
      spin_until(quiet, [&] { return quiet.bus_time_us() > wall_utime() + 3'000'000'000LL; }));
  quiet.publish("NODE_TEST_BUS_TIME", imu(1));
  ASSERT_TRUE(spin_until(listener, [&] { return !counters.seen.empty(); }));
  EXPECT_GT(counters.seen[0], static_cast<uint64_t>(wall_utime() + 3'000'000'000LL));
}

TEST(NodeTest, EveryNodePublishesItsStatus) {
  Node pub(kUrl, "status-pub"), sub(kUrl, "sub");
  pub.set_status_period(0.05);
  std::vector<std::string> names;
  sub.on<node_status_t>("NODE_STATUS", [&](const node_status_t& m) { names.push_back(m.node); });
  ASSERT_TRUE(spin_until(sub, [&] {
    pub.spin_once(10);
    for (const auto& n : names)
      if (n == "status-pub") return true;
    return false;
  }));
}

TEST(NodeTest, TimersRunAtTheirPeriodAndStopEndsRun) {
  Node node(kUrl, "timer");
  int ticks = 0;
  node.every(0.01, [&](int64_t) {
    if (++ticks == 10) node.stop();
  });
  const int64_t t0 = wall_utime();
  EXPECT_EQ(node.run(), 0);
  const double elapsed_s = 1e-6 * static_cast<double>(wall_utime() - t0);
  EXPECT_EQ(ticks, 10);
  EXPECT_GT(elapsed_s, 0.08);
  EXPECT_LT(elapsed_s, 1.0);
}

TEST(NodeTest, RegressionSignalDuringWaitEndsRunCleanly) {
  // SIGTERM arriving while LCM waited in select() used to throw "LCM handle failed".
  Node node(kUrl, "signalled");
  std::thread killer([] {
    std::this_thread::sleep_for(std::chrono::milliseconds(150));
    kill(getpid(), SIGTERM);
  });
  EXPECT_EQ(node.run(), 0);
  killer.join();
  EXPECT_TRUE(Node::signalled());
}

// The command line as a node parses it (NodeArgs::add_to, then finalize).
NodeArgs parse_args(std::vector<std::string> argv) {
  CLI::App app{"test"};
  NodeArgs args;
  args.add_to(app, false);
  argv.insert(argv.begin(), "node");
  std::vector<char*> c;
  for (auto& a : argv) c.push_back(a.data());
  app.parse(static_cast<int>(c.size()), c.data());
  args.finalize();
  return args;
}

TEST(NodeTest, RemapIsRepeatable) {
  const NodeArgs args =
      parse_args({"--remap", "IMU=NODE_TEST_IMU", "--remap", "MOCAP_POSE=NODE_TEST_POSE"});
  EXPECT_EQ(args.remap(channels::kImu), "NODE_TEST_IMU");
  EXPECT_EQ(args.remap(channels::kMocapPose), "NODE_TEST_POSE");
  EXPECT_EQ(args.remap(channels::kCamera), "CAMERA");
  EXPECT_TRUE(parse_args({}).remap.empty());
}

TEST(NodeTest, ABadRemapEndsTheNodeWithCode2) {
  EXPECT_THROW(parse_args({"--remap", "IMU"}), RemapError);
  EXPECT_THROW(parse_args({"--remap", "NO_SUCH_CHANNEL=X"}), RemapError);
  EXPECT_EQ(run_node_main("test",
                          [] {
                            parse_args({"--remap", "IMU"});
                            return 0;
                          }),
            2);
}

TEST(NodeTest, ARemappedNodeUsesTheNewNameEverywhere) {
  const NodeArgs args = parse_args({"--lcm-url", kUrl, "--remap", "IMU=NODE_TEST_REMAP_IMU",
                                    "--remap", "MOCAP_POSE=NODE_TEST_REMAP_POSE"});
  Node remapped(args, "remapped"), plain(kUrl, "plain");
  std::vector<int64_t> heard_by_plain, heard_by_remapped;
  plain.on<imu_t>("NODE_TEST_REMAP_IMU", [&](const imu_t& m) { heard_by_plain.push_back(m.seq); });
  remapped.on<pose_t>(channels::kMocapPose,
                      [&](const pose_t& m) { heard_by_remapped.push_back(m.utime); });
  remapped.publish(channels::kImu, imu(7));
  pose_t pose{};
  pose.utime = 42;
  pose.orientation[0] = 1;
  plain.publish("NODE_TEST_REMAP_POSE", pose);
  ASSERT_TRUE(spin_until(plain, [&] {
    remapped.spin_once(10);
    return !heard_by_plain.empty() && !heard_by_remapped.empty();
  }));
  EXPECT_EQ(heard_by_plain.at(0), 7);
  EXPECT_EQ(heard_by_remapped.at(0), 42);
  // Counters and NODE_STATUS name the channel as it is on LCM; the code's name finds it.
  EXPECT_EQ(remapped.channel_name(channels::kMocapPose), "NODE_TEST_REMAP_POSE");
  EXPECT_EQ(remapped.stats(channels::kMocapPose).received, 1u);
  EXPECT_FALSE(remapped.reject_value(channels::kMocapPose, "test"));
  EXPECT_EQ(remapped.stats("NODE_TEST_REMAP_POSE").rejected_values, 1u);
  const node_status_t st = remapped.status_message(1);
  ASSERT_EQ(st.n, 1);
  EXPECT_EQ(st.channels.at(0).channel, "NODE_TEST_REMAP_POSE");
}

TEST(NodeTest, BadUrlThrowsNamingIt) {
  try {
    Node node("nosuchprovider://foo", "bad");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nosuchprovider://foo"), std::string::npos);
  }
}

}  // namespace
}  // namespace alight
