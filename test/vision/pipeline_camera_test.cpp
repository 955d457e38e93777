// The pipeline under a real camera's effects (vision/pipeline.hpp; frontend/frame_checks.hpp,
// geometry/rolling_shutter.hpp), on rendered views of landing_a's platform: a rolling shutter's
// frames corrected to row 0, a global shutter's left exactly as they were, the driver's repeated
// frame and an exposure step refused with their own reasons while the tracks live on, and both
// lens models undistorted.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <optional>
#include <vector>

#include "common/build_paths.hpp"
#include "sim/params.hpp"
#include "sim/renderer.hpp"
#include "sim/scene.hpp"
#include "vision/pipeline.hpp"

namespace alight::vision {
namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;

struct Frame {
  cv::Mat image;
  int64_t utime = 0;
  PoseSample pose;
};

struct Views {
  sim::Scene scene;
  sim::CameraRig rig;
  Vector3d top = Vector3d::Zero();
};

Views landing_a() {
  const std::string root = alight::build::source_dir();
  Views v{sim::build_scene(sim::load_scenario(root + "/config/scenarios/landing_a.yaml"), 3),
          sim::load_camera_rig(root + "/config/vehicles/starmac.yaml", "downward"),
          {}};
  v.top = v.scene.platform->top_center_W;
  return v;
}

// The body at time t_s after `p0` at its constant velocity and body rate.
PoseSample advance(const PoseSample& p0, double t_s) {
  PoseSample p = p0;
  p.p_W_B = p0.p_W_B + p0.v_W_B * t_s;
  const double a = (p0.omega_B * t_s).norm();
  if (a > 0)
    p.q_WB = Quaterniond(p0.q_WB.toRotationMatrix() *
                         Eigen::AngleAxisd(a, p0.omega_B.normalized()).toRotationMatrix());
  p.utime = p0.utime + static_cast<int64_t>(std::llround(t_s * 1e6));
  return p;
}

// A frame whose row v is rendered from the camera line_delay_s x v after row 0 (in bands of 4
// rows); line_delay_s 0: a global shutter.
cv::Mat render(const Views& v, const sim::Renderer& renderer, const PoseSample& p0,
               double line_delay_s) {
  const int rows = renderer.model().height;
  if (line_delay_s == 0)
    return renderer.render(v.scene, camera_in_world(p0.X_WB(), v.rig.mount.X_BC()));
  cv::Mat acc(rows, renderer.model().width, CV_32F, cv::Scalar(0));
  for (int r0 = 0; r0 < rows; r0 += 4) {
    const int r1 = std::min(rows, r0 + 4);
    const PoseSample p = advance(p0, line_delay_s * 0.5 * (r0 + r1 - 1));
    renderer.accumulate_rows(v.scene, camera_in_world(p.X_WB(), v.rig.mount.X_BC()), 1.f, r0, r1,
                             acc);
  }
  cv::Mat out;
  acc.convertTo(out, CV_8U);
  return out;
}

// Seven frames at 10 Hz 1.7 m above the floor, passing over the platform at 0.4 m/s and turning
// at `omega_B` while each frame is read out.
std::vector<Frame> frames(const Views& v, const CameraModel& model, double line_delay_s,
                          const Vector3d& omega_B = Vector3d(0.3, -0.25, 0.15)) {
  const sim::Renderer renderer(model);
  std::vector<Frame> out;
  for (int i = 0; i < 7; ++i) {
    Frame f;
    f.utime = kT0 + i * 100'000;
    f.pose.utime = f.utime;
    f.pose.p_W_B = Vector3d(v.top.x() - 0.12, v.top.y() + 0.04, 1.7) + i * Vector3d(0.04, -0.01, 0);
    f.pose.q_WB = Quaterniond(rotation_from_rpy(0.01, -0.02, 0.2 + 0.004 * i));
    f.pose.v_W_B = Vector3d(0.4, -0.1, 0.0);
    f.pose.omega_B = omega_B;
    f.image = render(v, renderer, f.pose, line_delay_s);
    out.push_back(std::move(f));
  }
  return out;
}

// The pipeline over the frames; exposure 2 ms, so the blur guard does not refuse the turning
// frames.
std::vector<FrameResult> run(const Views& v, const CameraModel& model, const std::vector<Frame>& fs,
                             std::optional<double> line_delay_s) {
  Pipeline pipeline(Mission::kLanding, PipelineParams{}, model, v.rig.mount);
  std::vector<FrameResult> out;
  for (const auto& f : fs)
    out.push_back(pipeline.process(f.image, f.utime, f.pose, 0.002, line_delay_s));
  return out;
}

TEST(PipelineCameraTest, GlobalShutterResultsAreUnchangedToTheBit) {
  const Views v = landing_a();
  const auto fs = frames(v, v.rig.model, 0.0);
  const auto a = run(v, v.rig.model, fs, std::nullopt);
  const auto b = run(v, v.rig.model, fs, 0.0);
  ASSERT_TRUE(a.back().found()) << to_string(a.back().reason);
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].reason, b[i].reason) << i;
    EXPECT_EQ(a[i].n_matches, b[i].n_matches) << i;
    EXPECT_EQ(a[i].target.p_W, b[i].target.p_W) << i;
    EXPECT_EQ(a[i].target.height_m, b[i].target.height_m) << i;
  }
}

TEST(PipelineCameraTest, RollingShutterFramesAreCorrectedToRowZero) {
  const Views v = landing_a();
  const double line_delay_s = 40e-6;  // 19 ms of readout
  const auto fs = frames(v, v.rig.model, line_delay_s);
  const auto corrected = run(v, v.rig.model, fs, line_delay_s);
  const auto uncorrected = run(v, v.rig.model, fs, std::nullopt);
  const FrameResult& r = corrected.back();
  const FrameResult& u = uncorrected.back();
  std::printf(
      "corrected: %s, error %.4f m, height %.4f; uncorrected: %s, error %.4f m, height %.4f\n",
      to_string(r.reason), (r.target.p_W - v.top).norm(), r.target.height_m, to_string(u.reason),
      (u.target.p_W - v.top).norm(), u.target.height_m);
  ASSERT_TRUE(r.found()) << to_string(r.reason);
  EXPECT_LT((r.target.p_W - v.top).norm(), 0.02);
  EXPECT_NEAR(r.target.height_m, v.scene.platform->size_m.z(), 0.015);
  // The correction is what brings it there: the same frames taken for a global shutter's put
  // the platform several times farther off.
  if (u.found()) {
    EXPECT_LT((r.target.p_W - v.top).norm(), 0.5 * (u.target.p_W - v.top).norm());
  }
}

TEST(PipelineCameraTest, TheDriversRepeatIsRefusedAndTheTracksLiveOn) {
  const Views v = landing_a();
  auto fs = frames(v, v.rig.model, 0.0);
  fs[4].image = fs[3].image.clone();  // frame 4's stamp and pose, frame 3's pixels
  const auto rs = run(v, v.rig.model, fs, std::nullopt);
  EXPECT_EQ(rs[4].reason, Reason::kDuplicateFrame);
  EXPECT_EQ(rs[4].n_features, 0);
  EXPECT_TRUE(rs.back().found()) << to_string(rs.back().reason);
  // The reference is older than the repeat: the tracks ran across it.
  EXPECT_LT(rs.back().ref_utime, fs[4].utime);
}

TEST(PipelineCameraTest, AnExposureStepIsRefusedAndTheTracksLiveOn) {
  const Views v = landing_a();
  for (const double gain : {4.0, 0.25}) {
    SCOPED_TRACE(gain);
    auto fs = frames(v, v.rig.model, 0.0);
    fs[3].image.convertTo(fs[3].image, CV_8U, gain);
    const auto rs = run(v, v.rig.model, fs, std::nullopt);
    EXPECT_EQ(rs[3].reason, Reason::kExposureChange);
    EXPECT_TRUE(rs.back().found()) << to_string(rs.back().reason);
    EXPECT_LT((rs.back().target.p_W - v.top).norm(), 0.02);
  }
}

TEST(PipelineCameraTest, TheDetectorFollowsASmallerExposureChange) {
  const Views v = landing_a();
  const auto fs = frames(v, v.rig.model, 0.0);
  auto dim = fs;
  for (size_t i = 4; i < dim.size(); ++i) dim[i].image.convertTo(dim[i].image, CV_8U, 0.6);
  const auto plain = run(v, v.rig.model, fs, std::nullopt);
  const auto rs = run(v, v.rig.model, dim, std::nullopt);
  // -0.74 EV: taken, with the threshold scaled, so about the same blobs pass it.
  for (size_t i = 4; i < rs.size(); ++i) {
    EXPECT_NE(rs[i].reason, Reason::kExposureChange) << i;
    EXPECT_GT(rs[i].n_features, 0.85 * plain[i].n_features) << i;
  }
  EXPECT_TRUE(rs.back().found()) << to_string(rs.back().reason);
  EXPECT_LT((rs.back().target.p_W - v.top).norm(), 0.02);
}

TEST(PipelineCameraTest, BothLensModelsAreUndistorted) {
  const Views v = landing_a();
  CameraModel radtan = v.rig.model;
  radtan.D = {-0.25, 0.06, 0.0008, -0.0005, 0.0};
  CameraModel fisheye = v.rig.model;
  fisheye.distortion = CameraModel::Distortion::kEquidistant;
  fisheye.D = {0.04, -0.008, 0.0, 0.0, 0.0};
  for (const CameraModel& lens : {radtan, fisheye}) {
    SCOPED_TRACE(lens.distortion == CameraModel::Distortion::kEquidistant ? "fisheye" : "radtan");
    const auto fs = frames(v, lens, 0.0, Vector3d::Zero());
    const FrameResult r = run(v, lens, fs, std::nullopt).back();
    ASSERT_TRUE(r.found()) << to_string(r.reason);
    std::printf("error %.4f m, height %.4f\n", (r.target.p_W - v.top).norm(), r.target.height_m);
    EXPECT_LT((r.target.p_W - v.top).norm(), 0.02);
    EXPECT_NEAR(r.target.height_m, v.scene.platform->size_m.z(), 0.015);
  }
}

}  // namespace
}  // namespace alight::vision
