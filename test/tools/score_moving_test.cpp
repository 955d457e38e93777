// alight-score on a moving platform (issue 40): a synthetic log of a vehicle that descends onto
// a cart going at 1 m/s along x, in SIM_PLATFORM + SIM_TRUTH pairs at 50 Hz as alight-sim
// publishes them. The touch-down is judged relative to the platform; a log without SIM_PLATFORM
// scores as before.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tools/score.hpp"

namespace alight::tools {
namespace {

constexpr int64_t kMovingT0 = 1'790'000'000'000'000;
constexpr int64_t kTruthPeriod = 20'000;  // SIM_TRUTH's 50 Hz

struct DeckFlight {
  double deck_vz = 0.0;       // the deck's vertical speed around the contact [m/s]
  double sink = 0.3;          // the vehicle's sink rate in world [m/s]
  double offset_x = 0.04;     // where the vehicle comes down, from the top's centre [m]
  double yaw_deg = 12.0;      // the vehicle's heading
  double deck_yaw_deg = 185;  // the platform's
  bool with_platform_messages = true;
};

// The platform's top centre moves at 1 m/s along x from x = 0; the vehicle moves with it, its
// gear reaching the top at sample `kDeckContact`, landed 0.5 s later.
constexpr int kDeckContact = 100, kDeckSamples = 160;

Scorer fly_onto_deck(const DeckFlight& f, Scorer sc = Scorer()) {
  autonomy_status_t go{};
  go.utime = kMovingT0;
  go.mission = target_t::MISSION_LANDING;
  go.phase = autonomy_status_t::PHASE_DETECTION;
  go.phase_name = "DETECTION";
  sc.add(go);
  for (int k = 0; k < kDeckSamples; ++k) {
    const int64_t utime = kMovingT0 + k * kTruthPeriod;
    const double t = k * kTruthPeriod * 1e-6;
    const double deck_z = 0.2 + f.deck_vz * (t - kDeckContact * kTruthPeriod * 1e-6);
    platform_truth_t p{};
    p.utime = utime;
    p.version = platform_truth_t::VERSION;
    p.top_center_W[0] = 1.0 * t;
    p.top_center_W[2] = deck_z;
    p.yaw_rad = f.deck_yaw_deg * M_PI / 180;
    p.orientation[0] = std::cos(0.5 * p.yaw_rad);
    p.orientation[3] = std::sin(0.5 * p.yaw_rad);
    p.vel_W[0] = 1.0;
    p.vel_W[2] = f.deck_vz;
    p.size_m[0] = 0.432;
    p.size_m[1] = 0.279;
    p.size_m[2] = 0.2;
    if (f.with_platform_messages) sc.add(p);

    sim_truth_t s{};
    s.utime = utime;
    s.scenario = "landing_moving_cart";
    const bool on = k >= kDeckContact;
    s.pos[0] = p.top_center_W[0] + f.offset_x;
    s.pos[2] = on ? deck_z + 0.1 : deck_z + 0.1 + f.sink * (kDeckContact - k) * kTruthPeriod * 1e-6;
    s.vel[0] = 1.0;
    s.vel[2] = on ? f.deck_vz : -f.sink;
    s.orientation[0] = std::cos(0.5 * f.yaw_deg * M_PI / 180);
    s.orientation[3] = std::sin(0.5 * f.yaw_deg * M_PI / 180);
    s.has_platform = true;
    for (int i = 0; i < 3; ++i) {
      s.platform_center_W[i] = p.top_center_W[i];
      s.platform_size_m[i] = p.size_m[i];
    }
    s.platform_yaw_rad = p.yaw_rad;
    s.contact = on ? sim_truth_t::CONTACT_PLATFORM_TOP : sim_truth_t::CONTACT_NONE;
    s.landed = k >= kDeckContact + 25;
    sc.add(s);
  }
  autonomy_status_t landed = go;
  landed.utime = kMovingT0 + (kDeckContact + 30) * kTruthPeriod;
  landed.phase = autonomy_status_t::PHASE_LANDED;
  landed.phase_name = "LANDED";
  sc.add(landed);
  return sc;
}

std::string score_field(const Score& s, const std::string& key) {
  for (const auto& [k, v] : s.fields())
    if (k == key) return v;
  return "";
}

TEST(ScoreMovingTest, TouchdownRelativeToTheMovingPlatform) {
  const Score s = fly_onto_deck(DeckFlight{}).result();
  EXPECT_TRUE(s.success) << s.to_text();
  EXPECT_EQ(s.outcome, "landed");
  EXPECT_TRUE(s.platform_moving);
  // The platform went 2.6 m along x in the meantime; the error is against where it was.
  ASSERT_TRUE(s.touchdown_lateral_error_m);
  EXPECT_NEAR(*s.touchdown_lateral_error_m, 0.04, 1e-9);
  ASSERT_TRUE(s.touchdown_relative_sink_mps);
  EXPECT_NEAR(*s.touchdown_relative_sink_mps, 0.3, 1e-9);
  ASSERT_TRUE(s.touchdown_heading_error_deg);
  // 12 deg against 185 deg: 7 deg off the long axis taken the other way round.
  EXPECT_NEAR(*s.touchdown_heading_error_deg, 7.0, 1e-9);
  ASSERT_TRUE(s.touchdown_platform_speed_mps);
  EXPECT_NEAR(*s.touchdown_platform_speed_mps, 1.0, 1e-9);
  ASSERT_TRUE(s.mission_time_s);  // the time to land
  EXPECT_NEAR(*s.mission_time_s, (kDeckContact + 30) * kTruthPeriod * 1e-6, 1e-9);
  EXPECT_EQ(score_field(s, "platform_moving"), "true");
  EXPECT_EQ(score_field(s, "touchdown_heading_error_deg"), "7.0000");
}

// The square gear is turned to the top's edges modulo 90 deg: a vehicle square to the short
// edges, 3 deg off, is 3 deg off, not 87 (as the in-process loop scores it).
TEST(ScoreMovingTest, TheHeadingErrorIsToTheNearerEdgeOfTheTop) {
  DeckFlight f;
  f.yaw_deg = 30.0 + 87.0;
  f.deck_yaw_deg = 30.0;
  const Score s = fly_onto_deck(f).result();
  ASSERT_TRUE(s.touchdown_heading_error_deg);
  EXPECT_NEAR(*s.touchdown_heading_error_deg, 3.0, 1e-9);
  f.yaw_deg = 30.0 - 44.0;
  ASSERT_TRUE(fly_onto_deck(f).result().touchdown_heading_error_deg);
  EXPECT_NEAR(*fly_onto_deck(f).result().touchdown_heading_error_deg, 44.0, 1e-9);
}

TEST(ScoreMovingTest, AnImpactIsJudgedRelativeToTheDeck) {
  Scorer gear(1.0);  // takes 1 m/s
  // Sinking at 1.2 m/s in world onto a deck going down at 0.5 m/s: 0.7 m/s relative, landed.
  DeckFlight falling;
  falling.sink = 1.2;
  falling.deck_vz = -0.5;
  const Score a = fly_onto_deck(falling, gear).result();
  EXPECT_FALSE(a.crashed) << a.to_text();
  EXPECT_NEAR(*a.touchdown_relative_sink_mps, 0.7, 1e-9);
  EXPECT_NEAR(*a.max_touchdown_speed_mps, 0.7, 1e-9);
  // Sinking at 0.8 m/s onto a deck heaving up at 0.5 m/s: 1.3 m/s relative, a crash.
  DeckFlight rising;
  rising.sink = 0.8;
  rising.deck_vz = 0.5;
  const Score b = fly_onto_deck(rising, Scorer(1.0)).result();
  EXPECT_TRUE(b.crashed) << b.to_text();
  EXPECT_EQ(b.outcome, "crashed");
  EXPECT_NEAR(*b.touchdown_relative_sink_mps, 1.3, 1e-9);
}

TEST(ScoreMovingTest, WithoutSimPlatformTheScoreIsAsBefore) {
  DeckFlight f;
  f.with_platform_messages = false;
  const Score s = fly_onto_deck(f).result();
  EXPECT_FALSE(s.platform_moving);
  EXPECT_FALSE(s.touchdown_relative_sink_mps);
  for (const auto& [k, v] : s.fields()) {
    EXPECT_NE(k.rfind("platform_", 0), 0u) << k;
    EXPECT_EQ(k.find("relative"), std::string::npos) << k;
  }
  // Against the last sample's platform centre, as alight-score always measured.
  ASSERT_TRUE(s.touchdown_lateral_error_m);
  EXPECT_NEAR(*s.touchdown_lateral_error_m,
              1.0 * (kDeckSamples - 1 - kDeckContact - 25) * 0.02 - 0.04, 1e-9);
}

TEST(ScoreMovingTest, ANewerPlatformMessageVersionIsRefusedAndCounted) {
  Scorer sc;
  platform_truth_t p{};
  p.utime = kMovingT0;
  p.version = platform_truth_t::VERSION + 1;
  sc.add(p);
  const Score s = fly_onto_deck(DeckFlight{}, sc).result();
  EXPECT_EQ(s.platform_messages_refused, 1);
  EXPECT_TRUE(s.platform_moving);  // the current version's messages that followed
}

}  // namespace
}  // namespace alight::tools
