#include "vision/node/convert.hpp"

namespace alight::vision {

target_t to_msg(const FrameResult& r) {
  target_t m{};
  m.utime = r.utime;
  m.ref_utime = r.ref_utime;
  m.seq = r.seq;
  m.mission = static_cast<int8_t>(r.mission);
  m.found = r.found();
  m.reason = static_cast<int8_t>(r.reason);
  const bool has = r.found() || located_only(r.reason);
  for (int i = 0; i < 3; ++i) {
    m.p_W_target[i] = has ? r.target.p_W[i] : 0.0;
    m.n_W[i] = has ? r.target.n_W[i] : 0.0;
  }
  m.pixel[0] = has ? r.target.pixel.x() : 0.0;
  m.pixel[1] = has ? r.target.pixel.y() : 0.0;
  m.target_height_m = has ? r.target.height_m : 0.0;
  m.size_m[0] = has ? r.target.size_m[0] : 0.0;
  m.size_m[1] = has ? r.target.size_m[1] : 0.0;
  m.target_yaw_rad = has ? r.target.yaw_rad : 0.0;
  m.baseline_m = r.baseline_m;
  m.n_features = r.n_features;
  m.n_matches = r.n_matches;
  m.n_inliers_dominant = r.target.n_inliers_dominant;
  m.n_inliers_target = r.target.n_inliers_target;
  return m;
}

std::optional<platform_motion_t> to_platform_msg(const FrameResult& r) {
  if (!r.moving) return std::nullopt;
  const MovingTop& t = *r.moving;
  platform_motion_t m{};
  m.utime = r.utime;
  m.ref_utime = r.moving_ref_utime;
  m.seq = r.seq;
  m.version = platform_motion_t::VERSION;
  m.found = t.found();
  m.reason = static_cast<int8_t>(t.reason);
  m.n_candidates = t.n_candidates;
  m.n_inliers = t.n_inliers;
  m.outline = t.outline;
  if (!t.found()) return m;
  for (int i = 0; i < 3; ++i) {
    m.p_W[i] = t.p_W[i];
    m.v_W[i] = t.v_W[i];
    for (int j = 0; j < 3; ++j) {
      m.cov_p_W[3 * i + j] = t.cov_p_W(i, j);
      m.cov_v_W[3 * i + j] = t.cov_v_W(i, j);
    }
  }
  m.yaw_rad = t.yaw_rad;
  m.yaw_rate_rps = t.yaw_rate_rps;
  m.var_yaw = t.var_yaw;
  m.var_yaw_rate = t.var_yaw_rate;
  m.size_m[0] = t.size_m[0];
  m.size_m[1] = t.size_m[1];
  m.scale = t.scale;
  for (int i = 0; i < 3; ++i) {
    m.camera_W[i] = t.camera_W[i];
    m.ref_camera_W[i] = t.ref_camera_W[i];
  }
  m.plane_z_m = t.plane_z_m;
  return m;
}

}  // namespace alight::vision
