#include "tools/score.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <alight/image_t.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <numeric>
#include <random>

#include "common/build_paths.hpp"
#include "common/channels.hpp"

namespace alight::tools {
namespace {

constexpr int64_t kT0 = 1'790'000'000'000'000;

sim_truth_t landing_truth(int64_t utime, double x, double y, double z, bool landed) {
  sim_truth_t t{};
  t.utime = utime;
  t.scenario = "landing_b";
  t.pos[0] = x;
  t.pos[1] = y;
  t.pos[2] = z;
  t.orientation[0] = 1;
  t.has_platform = true;
  t.platform_center_W[0] = 1.0;
  t.platform_center_W[1] = -0.5;
  t.platform_center_W[2] = 0.219;
  t.platform_size_m[0] = 0.432;
  t.platform_size_m[1] = 0.279;
  t.platform_size_m[2] = 0.219;
  t.landed = landed;
  return t;
}

autonomy_status_t status(int64_t utime, int8_t phase, const char* name, double est_z = 0) {
  autonomy_status_t s{};
  s.utime = utime;
  s.mission = target_t::MISSION_LANDING;
  s.phase = phase;
  s.phase_name = name;
  s.has_estimate = phase >= autonomy_status_t::PHASE_REFINEMENT;
  s.estimate_W[0] = 1.01;
  s.estimate_W[1] = -0.5;
  s.estimate_W[2] = est_z;
  s.n_measurements = 12;
  return s;
}

Scorer landing_session(bool tip) {
  Scorer sc;
  sc.add(landing_truth(kT0, 0, 0, 1.5, false));
  sc.add(status(kT0 + 1'000'000, autonomy_status_t::PHASE_DETECTION, "DETECTION"));
  for (int i = 0; i < 5; ++i) {
    target_t t{};
    t.mission = target_t::MISSION_LANDING;
    t.found = i != 2;
    t.target_height_m = 0.22 + 0.002 * i;
    sc.add(t);
  }
  sc.add(status(kT0 + 5'000'000, autonomy_status_t::PHASE_REFINEMENT, "REFINEMENT", 0.25));
  sc.add(status(kT0 + 9'000'000, autonomy_status_t::PHASE_APPROACH, "APPROACH", 0.229));
  sc.add(status(kT0 + 10'000'000, autonomy_status_t::PHASE_APPROACH, "APPROACH", 0.3));
  sc.add(landing_truth(kT0 + 12'000'000, 1.03, -0.46, 0.25, false));
  auto touch = landing_truth(kT0 + 13'000'000, 1.03, -0.46, 0.24, !tip);
  touch.tipped = tip;
  sc.add(touch);
  // Later motion is not the touchdown; a tip, once seen, stays a failure.
  sc.add(landing_truth(kT0 + 14'000'000, 1.2, -0.46, 0.24, !tip));
  sc.add(status(kT0 + 13'500'000, autonomy_status_t::PHASE_LANDED, "LANDED", 0.3));
  return sc;
}

TEST(ScoreTest, LandingFiguresAgainstTruth) {
  const Score s = landing_session(false).result();
  EXPECT_TRUE(s.success);
  EXPECT_EQ(s.outcome, "landed");
  EXPECT_EQ(s.final_phase, "LANDED");
  ASSERT_TRUE(s.touchdown_lateral_error_m);
  EXPECT_NEAR(*s.touchdown_lateral_error_m, 0.05, 1e-9);  // (0.03, 0.04) from the centre
  ASSERT_TRUE(s.platform_height_error_m);
  EXPECT_NEAR(*s.platform_height_error_m, 0.229 - 0.219, 1e-9);  // estimate at convergence
  ASSERT_TRUE(s.vision_height_error_m);
  EXPECT_NEAR(*s.vision_height_error_m, 0.224 - 0.219, 1e-9);  // median of the found ones
  ASSERT_TRUE(s.mission_time_s);
  EXPECT_NEAR(*s.mission_time_s, 12.5, 1e-9);
  EXPECT_EQ(s.vision_frames, 5);
  EXPECT_EQ(s.vision_found, 4);
  EXPECT_FALSE(s.opening_width_error_m.has_value());
}

TEST(ScoreTest, TippedLandingFails) {
  const Score s = landing_session(true).result();
  EXPECT_FALSE(s.success);
  EXPECT_EQ(s.outcome, "tipped");
}

TEST(ScoreTest, LeavingTheFlyingAreaFailsEvenALanding) {
  Scorer sc = landing_session(false);
  sim_truth_t out = landing_truth(kT0 + 15'000'000, 1.2, -0.46, 0.24, true);
  out.out_of_area = true;  // the sim's flag is sticky: it stays set after a landing too
  sc.add(out);
  const Score s = sc.result();
  EXPECT_FALSE(s.success);
  EXPECT_EQ(s.outcome, "left_area");
  EXPECT_TRUE(s.out_of_area);
  EXPECT_NE(s.to_text().find("out_of_area: true"), std::string::npos) << s.to_text();
}

// A landing that ends upright, landed and 5 cm from the centre, touching the top while sinking
// at `sink_mps` (the samples either side of the contact 20 ms apart, as the sim sends them).
Scorer touchdown_at(double sink_mps, Scorer sc = Scorer(1.0)) {
  auto sample = [](int64_t utime, double z, double vz, int8_t contact, bool landed) {
    sim_truth_t t = landing_truth(utime, 1.03, -0.46, z, landed);
    t.vel[2] = vz;
    t.contact = contact;
    return t;
  };
  sc.add(status(kT0 + 1'000'000, autonomy_status_t::PHASE_DETECTION, "DETECTION"));
  // Resting on the floor at the start is no touch-down.
  sc.add(sample(kT0, 0.1, 0, sim_truth_t::CONTACT_FLOOR, false));
  sc.add(sample(kT0 + 2'000'000, 1.5, 0, sim_truth_t::CONTACT_NONE, false));
  sc.add(sample(kT0 + 12'000'000, 0.34, -sink_mps, sim_truth_t::CONTACT_NONE, false));
  sc.add(sample(kT0 + 12'020'000, 0.32, -0.5 * sink_mps, sim_truth_t::CONTACT_PLATFORM_TOP, false));
  sc.add(sample(kT0 + 14'000'000, 0.32, 0, sim_truth_t::CONTACT_PLATFORM_TOP, true));
  sc.add(status(kT0 + 14'000'000, autonomy_status_t::PHASE_LANDED, "LANDED", 0.3));
  return sc;
}

TEST(ScoreTest, TouchdownFasterThanTheGearTakesIsACrashEvenUprightOnTarget) {
  const Score s = touchdown_at(2.0).result();
  EXPECT_FALSE(s.success);
  EXPECT_EQ(s.outcome, "crashed");
  EXPECT_TRUE(s.crashed);
  ASSERT_TRUE(s.max_touchdown_speed_mps);
  EXPECT_DOUBLE_EQ(*s.max_touchdown_speed_mps, 2.0);  // the sample before the contact: the faster
  ASSERT_TRUE(s.touchdown_lateral_error_m);
  EXPECT_NEAR(*s.touchdown_lateral_error_m, 0.05, 1e-9);  // on target all the same
  const std::string text = s.to_text();
  EXPECT_NE(text.find("max_touchdown_speed_mps: 2.0000\ngear_max_impact_mps: 1.0000\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("n_collisions: 0\ncrashed: true\nout_of_area: false\n"), std::string::npos)
      << text;
}

TEST(ScoreTest, TouchdownWithinTheGearsImpactSpeedLands) {
  const Score s = touchdown_at(0.9).result();
  EXPECT_TRUE(s.success);
  EXPECT_EQ(s.outcome, "landed");
  EXPECT_FALSE(s.crashed);
  ASSERT_TRUE(s.max_touchdown_speed_mps);
  EXPECT_DOUBLE_EQ(*s.max_touchdown_speed_mps, 0.9);
  EXPECT_NE(s.to_text().find("crashed: false\n"), std::string::npos);
  // The limit is the vehicle's: a sturdier gear takes the 2 m/s above.
  EXPECT_TRUE(touchdown_at(2.0, Scorer(2.5)).result().success);
}

TEST(ScoreTest, EveryTouchdownCountsAndTheFastestIsReported) {
  Scorer sc = touchdown_at(0.5);
  // Knocked off the top afterwards and dropped onto the floor: a second touch-down, after the
  // landing, at whatever attitude.
  sim_truth_t fall = landing_truth(kT0 + 15'000'000, 1.4, -0.46, 0.5, false);
  fall.vel[2] = -3.0;
  fall.orientation[0] = 0;
  fall.orientation[1] = 1;  // upside down
  sc.add(fall);
  fall.utime += 20'000;
  fall.contact = sim_truth_t::CONTACT_FLOOR;
  fall.vel[2] = 0.4;  // bouncing back already
  sc.add(fall);
  const Score s = sc.result();
  EXPECT_EQ(s.outcome, "crashed");
  EXPECT_DOUBLE_EQ(*s.max_touchdown_speed_mps, 3.0);
}

TEST(ScoreTest, ContactSampleFasterThanTheOneBeforeCounts) {
  // Still accelerating when the contact sample was taken (thrust cut at contact).
  Scorer sc(1.0);
  sim_truth_t t = landing_truth(kT0, 1.0, -0.5, 0.4, false);
  t.vel[2] = -0.8;
  sc.add(t);
  t.utime += 20'000;
  t.vel[2] = -1.1;
  t.contact = sim_truth_t::CONTACT_PLATFORM_EDGE;
  sc.add(t);
  EXPECT_DOUBLE_EQ(*sc.result().max_touchdown_speed_mps, 1.1);
  EXPECT_TRUE(sc.result().crashed);
}

TEST(ScoreTest, NoTouchdownNoSpeedFigure) {
  const Score s = landing_session(false).result();  // SIM_TRUTH without contacts
  EXPECT_FALSE(s.max_touchdown_speed_mps.has_value());
  EXPECT_FALSE(s.crashed);
  EXPECT_EQ(s.to_text().find("max_touchdown_speed_mps"), std::string::npos);
  EXPECT_EQ(s.to_text().find("gear_max_impact_mps"), std::string::npos);
}

TEST(ScoreTest, IngressThroughTheOpening) {
  Scorer sc;
  auto truth = [&](int64_t utime, double x, bool collided) {
    sim_truth_t t{};
    t.utime = utime;
    t.scenario = "ingress";
    t.pos[0] = x;
    t.pos[1] = 0.02;
    t.pos[2] = 1.21;
    t.has_opening = true;
    t.opening_center_W[0] = 3.0;
    t.opening_center_W[2] = 1.2;
    t.opening_size_m[0] = 0.6;
    t.opening_size_m[1] = 0.6;
    t.wall_normal_W[0] = -1;  // approach from -x
    t.collided = collided;
    return t;
  };
  for (double w : {0.59, 0.61, 0.605, 0.9}) {
    target_t t{};
    t.mission = target_t::MISSION_INGRESS;
    t.found = true;
    t.size_m[0] = w;
    sc.add(t);
  }
  autonomy_status_t st{};
  st.mission = target_t::MISSION_INGRESS;
  st.phase = autonomy_status_t::PHASE_DETECTION;
  sc.add(st);
  st.phase = autonomy_status_t::PHASE_APPROACH;
  st.has_estimate = true;
  st.estimate_W[0] = 3.0;
  st.estimate_W[1] = 0.03;
  st.estimate_W[2] = 1.2;
  sc.add(st);
  sc.add(truth(kT0, 2.9, false));
  sc.add(truth(kT0 + 100'000, 3.1, false));  // crosses x = 3 halfway
  st.phase = autonomy_status_t::PHASE_DONE;
  st.phase_name = "DONE";
  sc.add(st);
  const Score s = sc.result();
  EXPECT_TRUE(s.success);
  EXPECT_EQ(s.outcome, "through");
  ASSERT_TRUE(s.opening_width_error_m);
  EXPECT_NEAR(*s.opening_width_error_m, 0.6075 - 0.6, 1e-9);  // median, the 0.9 outlier ignored
  ASSERT_TRUE(s.crossing_offset_m);
  EXPECT_NEAR(*s.crossing_offset_m, std::hypot(0.02, 0.01), 1e-9);
  ASSERT_TRUE(s.opening_center_error_m);
  EXPECT_NEAR(*s.opening_center_error_m, 0.03, 1e-9);

  sc.add(truth(kT0 + 200'000, 3.3, true));
  EXPECT_FALSE(sc.result().success);
  EXPECT_EQ(sc.result().outcome, "collided");
}

TEST(ScoreTest, RefusedOpeningIsItsOwnOutcome) {
  Scorer sc;
  sim_truth_t t{};
  t.utime = kT0;
  t.scenario = "ingress";
  t.pos[0] = 1.5;
  t.has_opening = true;
  t.opening_center_W[0] = 3.0;
  t.opening_size_m[0] = t.opening_size_m[1] = 0.6;
  t.wall_normal_W[0] = -1;
  target_t w{};
  w.mission = target_t::MISSION_INGRESS;
  w.found = true;
  w.size_m[0] = 0.595;
  sc.add(w);
  autonomy_status_t st{};
  st.mission = target_t::MISSION_INGRESS;
  st.phase = autonomy_status_t::PHASE_HOLD;
  st.phase_name = "HOLD";
  st.reason = "refused ingress: opening 0.595 x 0.600 m smaller than the vehicle + clearance";
  sc.add(st);
  sc.add(t);
  Score s = sc.result();
  EXPECT_FALSE(s.success);
  EXPECT_EQ(s.outcome, "refused");
  ASSERT_TRUE(s.opening_width_error_m);
  EXPECT_NEAR(*s.opening_width_error_m, -0.005, 1e-9);
  st.reason = "target lost (no target seen for 3.0 s); 2 retries exhausted: holding";
  sc.add(st);
  EXPECT_EQ(sc.result().outcome, "incomplete");
}

target_t vision_target(int64_t image_utime, bool found) {
  target_t t{};
  t.utime = image_utime;
  t.mission = target_t::MISSION_LANDING;
  t.found = found;
  t.reason = found ? target_t::REASON_OK : target_t::REASON_TOO_FEW_MATCHES;
  return t;
}

TEST(ScoreTest, LatencyPercentilesAreNearestRankOverKnownLatencies) {
  // Given 100 frames whose targets arrive 1, 2, ..., 100 ms after them, in shuffled order
  std::vector<int> latency_ms(100);
  std::iota(latency_ms.begin(), latency_ms.end(), 1);
  std::shuffle(latency_ms.begin(), latency_ms.end(), std::mt19937(7));
  Scorer sc;
  for (int i = 0; i < 100; ++i) {
    const int64_t exposure = kT0 + i * 200'000, received = exposure + 3'000;
    sc.add_camera_frame(exposure, received);
    sc.add(vision_target(exposure, true), received + latency_ms[i] * 1'000);
  }
  // Then the median is the 50th value, p99 the 99th, and every frame is covered
  const Score s = sc.result();
  ASSERT_TRUE(s.vision_latency_p50_ms && s.vision_latency_p99_ms && s.vision_latency_max_ms);
  EXPECT_DOUBLE_EQ(*s.vision_latency_p50_ms, 50.0);
  EXPECT_DOUBLE_EQ(*s.vision_latency_p99_ms, 99.0);
  EXPECT_DOUBLE_EQ(*s.vision_latency_max_ms, 100.0);
  EXPECT_EQ(s.vision_latency_unmatched, 0);
  ASSERT_TRUE(s.vision_frame_coverage);
  EXPECT_DOUBLE_EQ(*s.vision_frame_coverage, 1.0);
  EXPECT_EQ(s.camera_frames, 100);

  // With four latencies the nearest-rank median is the lower middle one, not their mean
  Scorer four;
  for (int i = 0; i < 4; ++i) {
    four.add_camera_frame(kT0 + i, kT0 + i * 100'000);
    four.add(vision_target(kT0 + i, false), kT0 + i * 100'000 + (4 - i) * 10'000);
  }
  const Score f = four.result();
  EXPECT_DOUBLE_EQ(*f.vision_latency_p50_ms, 20.0);
  EXPECT_DOUBLE_EQ(*f.vision_latency_p99_ms, 40.0);
}

TEST(ScoreTest, FramesProcessedWithoutAPoseAreCountedApartFromTheLatency) {
  // Given a session whose first five frames came before the pose source's first message (each
  // processed without a pose once it had waited 200 ms), then 100 frames at 1..100 ms
  Scorer sc;
  int64_t exposure = kT0;
  for (int i = 0; i < 5; ++i, exposure += 33'000) {
    sc.add_camera_frame(exposure, exposure + 3'000);
    target_t t = vision_target(exposure, false);
    t.reason = target_t::REASON_NO_POSE;
    sc.add(t, exposure + 203'000);
  }
  for (int i = 1; i <= 100; ++i, exposure += 33'000) {
    sc.add_camera_frame(exposure, exposure + 3'000);
    sc.add(vision_target(exposure, true), exposure + 3'000 + i * 1'000);
  }
  // Then the percentiles are the posed frames' alone, the five counted, every frame covered
  const Score s = sc.result();
  ASSERT_TRUE(s.vision_latency_p99_ms && s.vision_latency_max_ms);
  EXPECT_DOUBLE_EQ(*s.vision_latency_p99_ms, 99.0);
  EXPECT_DOUBLE_EQ(*s.vision_latency_max_ms, 100.0);
  EXPECT_EQ(s.vision_latency_without_pose, 5);
  EXPECT_EQ(s.vision_latency_unmatched, 0);
  ASSERT_TRUE(s.vision_frame_coverage);
  EXPECT_DOUBLE_EQ(*s.vision_frame_coverage, 1.0);
  EXPECT_EQ(s.vision_frames, 105);
}

TEST(ScoreTest, DroppedFramesLowerTheCoverageAndTheRates) {
  // Given 41 camera frames received 50 ms apart (a 2 s span) but exposed 25 ms apart (the sim
  // at half real time), of which the vision processed every fourth, 30 ms late, and found the
  // target in every other processed one
  Scorer sc;
  for (int k = 0; k <= 40; ++k) {
    const int64_t exposure = kT0 + k * 25'000, received = kT0 + 5'000'000 + k * 50'000;
    sc.add_camera_frame(exposure, received);
    if (k % 4 == 0 && k < 40) sc.add(vision_target(exposure, k % 8 == 0), received + 30'000);
  }
  const Score s = sc.result();
  EXPECT_EQ(s.vision_frames, 10);
  EXPECT_EQ(s.vision_found, 5);
  ASSERT_TRUE(s.camera_frames_per_s && s.vision_frames_per_s && s.vision_waypoints_per_s);
  EXPECT_DOUBLE_EQ(*s.camera_frames_per_s, 41 / 2.0);
  EXPECT_DOUBLE_EQ(*s.vision_frames_per_s, 10 / 2.0);
  EXPECT_DOUBLE_EQ(*s.vision_waypoints_per_s, 5 / 2.0);
  ASSERT_TRUE(s.vision_frame_coverage);
  EXPECT_DOUBLE_EQ(*s.vision_frame_coverage, 10 / 41.0);
  EXPECT_DOUBLE_EQ(*s.vision_latency_p50_ms, 30.0);
  EXPECT_DOUBLE_EQ(*s.vision_latency_max_ms, 30.0);
  // Latency is wall-clock: the sim's slower clock does not scale it
  ASSERT_TRUE(s.real_time_factor);
  EXPECT_DOUBLE_EQ(*s.real_time_factor, 0.5);
  const std::string text = s.to_text();
  EXPECT_NE(text.find("vision_frames_per_s: 5.0000\n"), std::string::npos) << text;
  EXPECT_NE(text.find("vision_frame_coverage: 0.2439\n"), std::string::npos) << text;
}

TEST(ScoreTest, TargetsWhoseCameraFrameIsMissingAreCountedNotMatched) {
  Scorer sc;
  // A target logged before its frame (out of order) still matches it
  sc.add(vision_target(kT0 + 1, true), kT0 + 1'040'000);
  sc.add_camera_frame(kT0 + 1, kT0 + 1'000'000);
  // Two targets of frames the logger never recorded
  sc.add(vision_target(kT0 + 2, true), kT0 + 1'100'000);
  sc.add(vision_target(kT0 + 3, false), kT0 + 1'200'000);
  const Score s = sc.result();
  EXPECT_EQ(s.vision_latency_unmatched, 2);
  ASSERT_TRUE(s.vision_latency_p50_ms);
  EXPECT_DOUBLE_EQ(*s.vision_latency_p50_ms, 40.0);
  EXPECT_DOUBLE_EQ(*s.vision_latency_max_ms, 40.0);
  EXPECT_DOUBLE_EQ(*s.vision_frame_coverage, 1.0);
  EXPECT_NE(s.to_text().find("vision_latency_unmatched: 2\n"), std::string::npos);

  // No camera frames at all: rates of the targets, no latency, no coverage, no crash
  Scorer none;
  none.add(vision_target(kT0 + 2, true), kT0);
  none.add(vision_target(kT0 + 3, true), kT0 + 500'000);
  const Score n = none.result();
  EXPECT_EQ(n.vision_latency_unmatched, 2);
  EXPECT_FALSE(n.vision_latency_p50_ms.has_value());
  EXPECT_FALSE(n.vision_frame_coverage.has_value());
  EXPECT_FALSE(n.camera_frames_per_s.has_value());
  ASSERT_TRUE(n.vision_waypoints_per_s);
  EXPECT_DOUBLE_EQ(*n.vision_waypoints_per_s, 4.0);
  EXPECT_EQ(n.to_text().find("vision_latency_p50_ms"), std::string::npos);
}

TEST(ScoreTest, TargetsWithoutReceiptTimesGiveNoTimingFigures) {
  const Score s = landing_session(false).result();
  EXPECT_FALSE(s.vision_latency_p50_ms.has_value());
  EXPECT_FALSE(s.vision_frames_per_s.has_value());
  EXPECT_FALSE(s.real_time_factor.has_value());
  EXPECT_EQ(s.vision_latency_unmatched, 0);
  EXPECT_EQ(s.to_text().find("_per_s"), std::string::npos) << s.to_text();
}

vision_timing_t timing(int64_t exposure, int64_t process_us, int64_t wait_us, int64_t processed) {
  vision_timing_t t{};
  t.utime = exposure;
  t.seq = processed;
  t.receive_utime = exposure + 2'000;
  t.wait_us = wait_us;
  t.process_us = process_us;
  t.process_cpu_us = process_us / 2;
  t.publish_utime = t.receive_utime + wait_us + process_us;
  t.total_us = wait_us + process_us;
  t.frames_received = processed + 3;
  t.frames_dropped = 2;
  t.frames_refused = 1;
  t.frames_processed = processed;
  return t;
}

// Issue 15: processing, the wait before it, and exposure-to-logger latency come apart.
TEST(ScoreTest, VisionTimingGivesProcessingWaitAndEndToEndPercentilesApart) {
  // Given 100 frames on the wall clock: processing 1..100 tenths of a ms, waits of 10..1000 us
  // in another order, and each target received by the logger 20 + i ms after its exposure
  std::vector<int> order(100);
  std::iota(order.begin(), order.end(), 1);
  std::shuffle(order.begin(), order.end(), std::mt19937(3));
  Scorer sc;
  for (int i = 0; i < 100; ++i) {
    const int64_t exposure = kT0 + i * 16'667;
    sc.add(vision_target(exposure, true), exposure + (20 + i) * 1'000);
    sc.add(timing(exposure, order[i] * 100, (101 - order[i]) * 10, i + 1));
  }
  // A message the logger delivered late does not turn the counters back
  sc.add(timing(kT0, 50, 50, 7));
  const Score s = sc.result();
  EXPECT_EQ(s.timing_frames, 101);
  ASSERT_TRUE(s.vision_process_ms && s.vision_wait_ms && s.vision_end_to_end_ms);
  EXPECT_DOUBLE_EQ(s.vision_process_ms->p50, 5.0);  // 101 values: the extra 0.05 ms is 1st
  EXPECT_DOUBLE_EQ(s.vision_process_ms->p90, 9.0);
  EXPECT_DOUBLE_EQ(s.vision_process_ms->p99, 9.9);
  EXPECT_DOUBLE_EQ(s.vision_process_ms->max, 10.0);
  EXPECT_DOUBLE_EQ(s.vision_wait_ms->max, 1.0);
  ASSERT_TRUE(s.vision_process_cpu_ms);  // its own percentiles, not the wall-clock ones
  EXPECT_DOUBLE_EQ(s.vision_process_cpu_ms->max, 5.0);
  EXPECT_DOUBLE_EQ(s.vision_end_to_end_ms->p50, 69.0);
  EXPECT_DOUBLE_EQ(s.vision_end_to_end_ms->p99, 118.0);
  EXPECT_DOUBLE_EQ(s.vision_end_to_end_ms->max, 119.0);
  EXPECT_EQ(s.vision_frames_processed, 100);
  EXPECT_EQ(s.vision_frames_received, 103);
  EXPECT_EQ(s.vision_frames_dropped, 2);
  EXPECT_EQ(s.vision_frames_refused, 1);
  const std::string text = s.to_text();
  EXPECT_NE(text.find("vision_process_p99_ms: 9.9000\n"), std::string::npos) << text;
  EXPECT_NE(text.find("vision_wait_p50_ms: "), std::string::npos) << text;
  EXPECT_NE(text.find("vision_end_to_end_p90_ms: 109.0000\n"), std::string::npos) << text;
  EXPECT_NE(text.find("vision_frames_dropped: 2\n"), std::string::npos) << text;
}

TEST(ScoreTest, EndToEndNeedsExposureStampsOnTheWallClock) {
  // The simulator's own clock (a scenario's start_utime, years before the logger's stamps)
  Scorer sc;
  for (int i = 0; i < 10; ++i) {
    sc.add(vision_target(1'700'000'000'000'000 + i, true), kT0 + i);
    sc.add(timing(1'700'000'000'000'000 + i, 4'000, 100, i + 1));
  }
  const Score s = sc.result();
  ASSERT_TRUE(s.vision_process_ms);
  EXPECT_DOUBLE_EQ(s.vision_process_ms->p50, 4.0);
  EXPECT_FALSE(s.vision_end_to_end_ms.has_value());
  EXPECT_EQ(s.to_text().find("end_to_end"), std::string::npos);
  // And without VISION_TIMING none of these figures appear
  EXPECT_EQ(landing_session(false).result().to_text().find("timing_frames"), std::string::npos);
}

TEST(ScoreTest, JsonQuotesStringsAndNotNumbers) {
  const std::string j = landing_session(false).result().to_json();
  EXPECT_NE(j.find("\"success\": true"), std::string::npos) << j;
  EXPECT_NE(j.find("\"scenario\": \"landing_b\""), std::string::npos) << j;
  EXPECT_NE(j.find("\"touchdown_lateral_error_m\": 0.0500"), std::string::npos) << j;
}

// The command line on a log written by LCM's writer: text, JSON and exit codes.
TEST(ScoreTest, CommandLineReadsASessionLog) {
  const auto path = std::filesystem::temp_directory_path() / "alight_score_test.lcmlog";
  {
    lcm::LogFile log(path.string(), "w");
    auto write_at = [&](const char* ch, const auto& msg, int64_t received_utime) {
      std::vector<uint8_t> buf(msg.getEncodedSize());
      msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
      lcm::LogEvent ev{0, received_utime, ch, static_cast<int32_t>(buf.size()), buf.data()};
      log.writeEvent(&ev);
    };
    auto write = [&](const char* ch, const auto& msg) { write_at(ch, msg, msg.utime); };
    write(channels::kSimTruth, landing_truth(kT0, 0, 0, 1.5, false));
    write(channels::kAutonomyStatus,
          status(kT0 + 1, autonomy_status_t::PHASE_DETECTION, "DETECTION"));
    // Two frames 0.5 s apart, each answered by the vision 120 ms (wall) after the logger got it
    for (int i = 0; i < 2; ++i) {
      image_t img{};
      img.utime = kT0 + 10 + i;
      img.width = img.height = img.row_stride = 2;
      img.pixelformat = image_t::PIXEL_FORMAT_GRAY;
      img.size = 4;
      img.data.assign(4, 128);
      write_at(channels::kCamera, img, kT0 + 1'000'000 + i * 500'000);
      write_at(channels::kVisionTarget, vision_target(img.utime, i == 1),
               kT0 + 1'120'000 + i * 500'000);
      write_at(channels::kVisionTiming, timing(img.utime, 3'000 + i * 1'000, 500, i + 1),
               kT0 + 1'121'000 + i * 500'000);
    }
    write(channels::kSimTruth, landing_truth(kT0 + 2, 1.0, -0.5, 0.24, true));
  }
  const std::string bin = std::string(alight::build::binary_dir()) + "/bin/alight-score ";
  auto run = [&](const std::string& args, std::string* out) {
    FILE* p = popen((bin + args + " 2>&1").c_str(), "r");
    char buf[512];
    while (fgets(buf, sizeof buf, p)) *out += buf;
    return WEXITSTATUS(pclose(p));
  };
  std::string text, json, missing;
  EXPECT_EQ(run(path.string(), &text), 0) << text;
  EXPECT_NE(text.find("outcome: landed\n"), std::string::npos) << text;
  EXPECT_NE(text.find("touchdown_lateral_error_m: 0.0000\n"), std::string::npos) << text;
  EXPECT_NE(text.find("vision_latency_p99_ms: 120.0000\n"), std::string::npos) << text;
  EXPECT_NE(text.find("camera_frames: 2\n"), std::string::npos) << text;
  EXPECT_NE(text.find("vision_frame_coverage: 1.0000\n"), std::string::npos) << text;
  EXPECT_NE(text.find("vision_process_max_ms: 4.0000\n"), std::string::npos) << text;
  EXPECT_NE(text.find("vision_frames_processed: 2\n"), std::string::npos) << text;
  EXPECT_EQ(run(path.string() + " --json", &json), 0);
  EXPECT_EQ(json.front(), '{');
  EXPECT_NE(json.find("\"vision_process_p50_ms\": 3.0000"), std::string::npos) << json;
  EXPECT_EQ(run("/nonexistent.lcmlog", &missing), 105);  // CLI11: the file does not exist

  // --vision-only: a log with VISION_TIMING and no SIM_TRUTH is fine, one without is not
  const auto bare = std::filesystem::temp_directory_path() / "alight_score_test_bare.lcmlog";
  {
    lcm::LogFile log(bare.string(), "w");
    const vision_timing_t t = timing(kT0, 2'500, 100, 1);
    std::vector<uint8_t> buf(t.getEncodedSize());
    t.encode(buf.data(), 0, static_cast<int>(buf.size()));
    lcm::LogEvent ev{0, kT0 + 5'000, channels::kVisionTiming, static_cast<int32_t>(buf.size()),
                     buf.data()};
    log.writeEvent(&ev);
  }
  std::string vision, no_truth, no_timing;
  EXPECT_EQ(run(bare.string() + " --vision-only", &vision), 0) << vision;
  EXPECT_NE(vision.find("vision_process_p50_ms: 2.5000\n"), std::string::npos) << vision;
  EXPECT_EQ(run(bare.string(), &no_truth), 2) << no_truth;
  EXPECT_EQ(run(path.string() + " --vision-only --timing-channel NONE", &no_timing), 2);
  std::filesystem::remove(path);
  std::filesystem::remove(bare);
}

// The vehicle's gear from --vehicle; without it the default vehicle's; a refused vehicle file is
// a configuration error (exit 2) naming the file.
TEST(ScoreTest, CommandLineJudgesTouchdownsAgainstTheVehiclesGear) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("alight_score_gear_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto log_path = (dir / "crash.lcmlog").string();
  {
    lcm::LogFile log(log_path, "w");
    auto write = [&](const char* ch, const auto& msg) {
      std::vector<uint8_t> buf(msg.getEncodedSize());
      msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
      lcm::LogEvent ev{0, msg.utime, ch, static_cast<int32_t>(buf.size()), buf.data()};
      log.writeEvent(&ev);
    };
    write(channels::kAutonomyStatus,
          status(kT0 + 1, autonomy_status_t::PHASE_DETECTION, "DETECTION"));
    sim_truth_t t = landing_truth(kT0, 1.0, -0.5, 0.5, false);
    t.vel[2] = -2.0;
    write(channels::kSimTruth, t);
    t = landing_truth(kT0 + 20'000, 1.0, -0.5, 0.32, true);
    t.contact = sim_truth_t::CONTACT_PLATFORM_TOP;
    write(channels::kSimTruth, t);
  }
  std::ofstream(dir / "sturdy.yaml") << "vehicle:\n  gear_max_impact_mps: 3.0\n";
  const std::string fifo = (dir / "fifo.yaml").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string bin =
      std::string(alight::build::binary_dir()) + "/bin/alight-score " + log_path;
  auto run = [&](const std::string& args, std::string* out) {
    FILE* p = popen((bin + args + " 2>&1").c_str(), "r");
    char buf[512];
    while (fgets(buf, sizeof buf, p)) *out += buf;
    return WEXITSTATUS(pclose(p));
  };
  std::string plain, pelican, sturdy, refused, help;
  EXPECT_EQ(run("", &plain), 1) << plain;
  EXPECT_NE(plain.find("outcome: crashed\n"), std::string::npos) << plain;
  EXPECT_NE(plain.find("max_touchdown_speed_mps: 2.0000\n"), std::string::npos) << plain;
  EXPECT_EQ(run(" --vehicle " + std::string(alight::build::source_dir()) +
                    "/config/vehicles/pelican.yaml",
                &pelican),
            1)
      << pelican;
  EXPECT_NE(pelican.find("crashed: true\n"), std::string::npos) << pelican;
  EXPECT_EQ(run(" --vehicle " + (dir / "sturdy.yaml").string(), &sturdy), 0) << sturdy;
  EXPECT_NE(sturdy.find("outcome: landed\n"), std::string::npos) << sturdy;
  EXPECT_NE(sturdy.find("gear_max_impact_mps: 3.0000\n"), std::string::npos) << sturdy;
  EXPECT_EQ(run(" --vehicle " + fifo, &refused), 2) << refused;
  EXPECT_NE(refused.find(fifo + ": not a regular file (a FIFO)"), std::string::npos) << refused;
  EXPECT_EQ(run(" --help", &help), 0);
  EXPECT_NE(help.find("gear_max_impact_mps"), std::string::npos) << help;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace alight::tools
