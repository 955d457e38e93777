#pragma once
// Rendered frame sequences (alight_sim, issue 3) for the mission tests: a camera moving along a
// straight line over known poses, each frame fed to the pipeline with its true pose.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "common/build_paths.hpp"
#include "sim/params.hpp"
#include "sim/renderer.hpp"
#include "sim/scene.hpp"
#include "vision/pipeline.hpp"

namespace alight::vision::testing {

struct Frame {
  cv::Mat image;
  int64_t utime = 0;
  PoseSample pose;
};

struct Sequence {
  sim::Scene scene;
  sim::CameraRig rig;
  std::vector<Frame> frames;
};

/// n frames at 10 Hz from p_start to p_start + step * (n - 1), attitude rpy (Z-Y-X) fixed but
/// for a small yaw drift. Mount "downward" or "forward" of starmac.yaml.
inline Sequence render_sequence(const std::string& scenario_file, uint64_t seed,
                                const std::string& mount, const Vector3d& p_start,
                                const Vector3d& step, const Vector3d& rpy, int n) {
  const std::string root = alight::build::source_dir();
  const auto scenario = sim::load_scenario(root + "/config/scenarios/" + scenario_file);
  Sequence s{sim::build_scene(scenario, seed),
             sim::load_camera_rig(root + "/config/vehicles/starmac.yaml", mount),
             {}};
  const sim::Renderer renderer(s.rig.model);
  for (int i = 0; i < n; ++i) {
    Frame f;
    f.utime = 1'700'000'000'000'000 + i * 100'000;
    f.pose.utime = f.utime;
    f.pose.p_W_B = p_start + i * step;
    f.pose.q_WB = Quaterniond(rotation_from_rpy(rpy.x(), rpy.y(), rpy.z() + 0.004 * i));
    f.image = renderer.render(s.scene, camera_in_world(f.pose.X_WB(), s.rig.mount.X_BC()));
    s.frames.push_back(std::move(f));
  }
  return s;
}

inline std::vector<FrameResult> run(const Sequence& s, Mission mission,
                                    const PipelineParams& params = {}) {
  Pipeline pipeline(mission, params, s.rig.model, s.rig.mount);
  std::vector<FrameResult> out;
  for (const auto& f : s.frames) out.push_back(pipeline.process(f.image, f.utime, f.pose));
  return out;
}

}  // namespace alight::vision::testing
