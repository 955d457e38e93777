// Landing diagnostics: one scene flown in process with the real vision, every frame's
// outcome printed against the simulator's truth (with --no-mocap also the onboard estimate's
// camera position error): reason, the platform's inliers and the floor's,
// how much of the true platform top is in the image, and when found the waypoint's error, the
// measured extent (long, short) minus the true size and the height error; autonomy's phase and
// waypoint count. On a moving platform also the body's offset from the top's centre, the moving
// top's measurement (cut by the border or not) and the platform filter's prediction against the
// truth. With --dump DIR the frames (true top outline green, measured red, features
// coloured by label, the moving top's set as magenta crosses) are written as PNG for a look.
//
//   build/bin/alight_landing_diag --scenario FILE [--seed N] [--no-mocap] [--dump DIR] [--every K]

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "autonomy/convert.hpp"
#include "closed_loop.hpp"
#include "common/build_paths.hpp"
#include "common/params.hpp"
#include "sim/params.hpp"
#include "sim/platform_motion.hpp"
#include "sim/scene.hpp"
#include "vision/node/convert.hpp"
#include "vision/params.hpp"
#include "vision/pipeline.hpp"

using namespace alight;
using namespace alight::autonomy;
using namespace alight::autonomy::test;

int main(int argc, char** argv) try {
  CLI::App app{"landing diagnostics: per-frame vision against the truth"};
  std::string scenario_file, dump;
  std::string vehicle = std::string(alight::build::source_dir()) + "/config/vehicles/pelican.yaml";
  uint64_t seed = 1;
  std::string shadow_prior;
  int every = 1;
  app.add_option("--scenario", scenario_file)->required();
  app.add_option("--shadow-prior", shadow_prior,
                 "also run a second pipeline with this vision.landing.floor_prior on the frames "
                 "(its outcome printed after 'shadow'; the flight uses the vehicle file's)");
  app.add_option("--seed", seed);
  app.add_option("--vehicle", vehicle);
  app.add_option("--dump", dump,
                 "write every --every-th frame as PNG into this folder (made if missing)");
  app.add_option("--every", every);
  double time_limit_s = 240;
  app.add_option("--time-limit", time_limit_s, "simulated seconds after the start at most");
  bool no_mocap = false;
  app.add_flag("--no-mocap", no_mocap,
               "fly on the onboard estimate (each frame then prints the camera's estimate error)");
  CLI11_PARSE(app, argc, argv);
  cv::setNumThreads(1);
  if (!dump.empty()) {
    // A missing folder made every frame's write fail without a word.
    std::error_code ec;
    std::filesystem::create_directories(dump, ec);
    if (ec || !std::filesystem::is_directory(dump)) {
      std::fprintf(stderr, "alight_landing_diag: --dump %s: cannot make the folder (%s)\n",
                   dump.c_str(), ec.message().c_str());
      return 2;
    }
  }

  const auto scenario = sim::load_scenario(scenario_file);
  // The truth is the scene the closed loop's simulator flies in (the scenario's randomize drawn
  // as it draws it).
  const auto scene = sim::simulated_scene(scenario, seed);
  // A scene without a platform (landing_none_photo) is flown against a zero-size "platform" at
  // the world origin on the floor: every target found is false, its errors are its position,
  // size and height.
  sim::PlatformTruth P;
  P.top_center_W = Vector3d::Zero();
  P.size_m = Vector3d::Zero();
  if (scene.platform) {
    P = *scene.platform;
    std::printf("# platform top centre (%.3f %.3f %.3f) size %.3f x %.3f x %.3f yaw %.1f deg\n",
                P.top_center_W.x(), P.top_center_W.y(), P.top_center_W.z(), P.size_m.x(),
                P.size_m.y(), P.size_m.z(), P.yaw_rad * 180 / M_PI);
  } else {
    std::printf("# no platform: a target's dC is its position, its size and dh its own\n");
  }
  // A moving platform's top where it is at a frame's time: its path and turn as the simulator
  // moves it (the sea state's draws are not the simulator's, so a deck's heave, roll and pitch
  // are left out: the corners are the level top's).
  std::optional<sim::PlatformMotion> motion;
  if (scene.platform && scenario.platform && scenario.platform->moving)
    motion.emplace(scenario.platform->motion, P.top_center_W, P.yaw_rad, 0);
  const auto moved_at = [&](int64_t utime) -> std::optional<sim::PlatformPose> {
    if (!motion) return std::nullopt;
    return motion->at(1e-6 * double(utime - scenario.start_utime));
  };
  const auto corners_at = [&](const std::optional<sim::PlatformPose>& moved) {
    std::vector<Vector3d> corners_W;
    if (!scene.platform) return corners_W;  // no corners in view
    const Vector3d centre = moved ? moved->top_center_W : P.top_center_W;
    const double yaw = moved ? moved->yaw_rad : P.yaw_rad;
    const double c = std::cos(yaw), s = std::sin(yaw);
    for (const auto& [a, b] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
      const double x = a * P.size_m.x() / 2, y = b * P.size_m.y() / 2;
      corners_W.push_back(centre + Vector3d(c * x - s * y, s * x + c * y, 0));
    }
    return corners_W;
  };
  const auto params = vision::load_node_params(vehicle);
  // The camera as rendered: the vision undistorts with the scenario's lens, as the node does.
  auto rig = sim::load_camera_rig(vehicle, "downward");
  rig.model = sim::with_lens(rig.model, scenario.camera.effects);
  vision::Pipeline pipeline(vision::Mission::kLanding, params.pipeline, rig.model, rig.mount);
  auto shadow_params = params.pipeline;
  if (!shadow_prior.empty()) shadow_params.landing.floor_prior = shadow_prior;
  vision::Pipeline shadow(vision::Mission::kLanding, shadow_params, rig.model, rig.mount);
  Phase phase = Phase::kIdle;
  int n_waypoints = 0;
  // The platform filter's state after the last step (autonomy/platform_filter.hpp).
  struct {
    int fused = 0, run = 0, refused = 0;           // fused, in a row within the gate, refused
    int gate = 0, order = 0, size = 0, reach = 0;  // refused by the gate, as out of order, as too
                                                   // large, as beyond the platform's reach
    bool believed = false;
    std::optional<PlatformFilter> copy;  // autonomy's, for its prediction at a frame's time
  } filter;
  ClosedLoopConfig cfg;
  cfg.vehicle_file = vehicle;
  cfg.scenario_file = scenario_file;
  cfg.mission = Mission::kLanding;
  cfg.seed = seed;
  cfg.time_limit_s = time_limit_s;
  cfg.onboard_estimate = no_mocap;
  // The onboard estimator's verdict on the frame the vision is about to read (without motion
  // capture): the front end's reason, the filter's outcome, the fit's inliers and its other
  // motions' (the second fit of a platform moving under the camera), and the running counts of
  // samples fused on the other motion and with inflated noise.
  std::string flow_note;
  std::optional<estimator::FlowSample> flow_sample;
  cfg.on_flow_frame = [&](const estimator::Onboard& o) {
    const auto& f = o.last_frame();
    flow_sample = f.sample;
    flow_note = std::string(" | flow ") + estimator::to_string(f.flow) + " " +
                estimator::to_string(f.fused);
    if (f.sample) {
      flow_note += " in " + std::to_string(f.sample->inliers);
      for (const auto& m : f.sample->others) flow_note += " other " + std::to_string(m.inliers);
    }
    const auto c = o.state().counters;
    flow_note += " second " + std::to_string(c.flow_second) + " inflated " +
                 std::to_string(c.flow_inflated) + " resets " +
                 std::to_string(c.flow_velocity_resets);
  };
  // Autonomy's reason within a phase, printed where its words change (its figures change each
  // step): what the vehicle waits for.
  std::string said;
  const auto words = [](const std::string& r) {
    return r.substr(0, r.find_first_of("(0123456789"));
  };
  cfg.script = [&](const Autonomy& a, double t, ScriptActions&) {
    if (a.phase() != phase)
      std::printf("# phase %s -> %s (retries %d): %s\n", phase_name(phase), phase_name(a.phase()),
                  a.retries(), a.reason().c_str());
    else if (words(a.reason()) != said)
      std::printf("# %.3f reason: %s\n", t, a.reason().c_str());
    said = words(a.reason());
    phase = a.phase();
    n_waypoints = a.estimator().n();
    const auto& pf = a.platform_filter();
    filter.fused = pf.n_updates();
    filter.run = pf.n_consistent();
    filter.refused = pf.n_rejected();
    filter.gate = pf.n_refused(PlatformFilter::Refusal::kGate);
    filter.order = pf.n_refused(PlatformFilter::Refusal::kOutOfOrder);
    filter.size = pf.n_refused(PlatformFilter::Refusal::kLargerThanTheTop);
    filter.reach = pf.n_refused(PlatformFilter::Refusal::kBeyondReach);
    filter.believed = pf.believed();
    filter.copy = pf;
  };
  int n = 0;
  std::optional<platform_motion_t> platform;  // the last frame's VISION_PLATFORM
  // Each frame's camera pose from motion capture (as the vision gets it) and the truth, to tell
  // how far the motion the vision assumes between reference and current is off.
  std::map<int64_t, std::pair<Isometry3d, Isometry3d>> cams;
  std::map<int64_t, Isometry3d> truth_cams;  // the last frames' true camera poses
  cfg.camera_vision = [&](const sim::CameraFrame& f, const std::optional<PoseSample>& pose) {
    const auto r = pipeline.process(f.pixels, f.utime, pose, f.exposure_s, f.line_delay_s);
    if (pose) cams[f.utime] = {camera_in_world(pose->X_WB(), rig.mount.X_BC()), f.X_WC};
    truth_cams[f.utime] = f.X_WC;
    while (truth_cams.size() > 4) truth_cams.erase(truth_cams.begin());
    while (!cams.empty() && cams.begin()->first < f.utime - 5000000) cams.erase(cams.begin());
    const Isometry3d X_CW = f.X_WC.inverse();
    std::vector<cv::Point> truth_px;
    int in_image = 0;
    const std::optional<sim::PlatformPose> moved = moved_at(f.utime);
    for (const auto& p : corners_at(moved))
      if (const auto px = rig.model.project(X_CW * p)) {
        truth_px.emplace_back(static_cast<int>(px->x()), static_cast<int>(px->y()));
        in_image +=
            px->x() >= 0 && px->y() >= 0 && px->x() < rig.model.width && px->y() < rig.model.height;
      }
    const Vector3d cam = f.X_WC.translation();
    std::printf("%7.3f %-13s n%-2d cam(%+.2f %+.2f %.2f) %-18s m %3d in %3d/%3d corners %d",
                (f.utime - 1700000000000000) * 1e-6, phase_name(phase), n_waypoints, cam.x(),
                cam.y(), cam.z(), vision::to_string(r.reason), r.n_matches,
                r.target.n_inliers_target, r.target.n_inliers_dominant, in_image);
    if (no_mocap && pose) {  // the onboard estimate's camera position minus the true one
      const Vector3d e = camera_in_world(pose->X_WB(), rig.mount.X_BC()).translation() - cam;
      std::printf(" est err(%+.3f %+.3f %+.3f)", e.x(), e.y(), e.z());
    }
    {  // floor inliers inside the hull of the top's inliers (a top hides the floor under it)
      std::vector<cv::Point2f> top_px, hull;
      for (size_t i = 0; i < r.matched_px.size() && i < r.labels.size(); ++i)
        if (r.labels[i] == vision::Label::kTarget)
          top_px.emplace_back(r.matched_px[i].x(), r.matched_px[i].y());
      int inside = 0;
      if (top_px.size() >= 3) {
        cv::convexHull(top_px, hull);
        for (size_t i = 0; i < r.matched_px.size() && i < r.labels.size(); ++i)
          if (r.labels[i] == vision::Label::kDominant &&
              cv::pointPolygonTest(hull, cv::Point2f(r.matched_px[i].x(), r.matched_px[i].y()),
                                   true) > 2.0)
            ++inside;
      }
      std::printf(" fin %d", inside);
    }
    {  // matches on the true top (inside its outline by more than 2 px), and of them the top's
      // inliers: few on the top is a blank top, many but none labelled is the planes' doing
      int on = 0, on_labelled = 0;
      if (truth_px.size() == 4)
        for (size_t i = 0; i < r.matched_px.size(); ++i)
          if (cv::pointPolygonTest(truth_px, cv::Point2f(r.matched_px[i].x(), r.matched_px[i].y()),
                                   true) > 2.0) {
            ++on;
            on_labelled += i < r.labels.size() && r.labels[i] == vision::Label::kTarget;
          }
      std::printf(" on %d/%d", on_labelled, on);
    }
    // The floor's smear over this frame's exposure [px], as the pipeline's guard saw it (0 with
    // the guard off).
    std::printf(" blur %.1f", r.blur_px);
    // The body's turn rate and speed the guard saw (motion capture's) [rad/s, m/s].
    if (pose)
      std::printf(" w %.2f (%+.2f %+.2f %+.2f) v %.2f", pose->omega_B.norm(), pose->omega_B.x(),
                  pose->omega_B.y(), pose->omega_B.z(), pose->v_W_B.norm());
    std::printf(" gain %.2f", f.gain);  // the camera's, flicker and automatic gain
    if (moved)  // the moving platform's truth: where it is relative to the camera, its velocity
      std::printf(" plat rel(%+.2f %+.2f) v(%+.2f %+.2f)", moved->top_center_W.x() - cam.x(),
                  moved->top_center_W.y() - cam.y(), moved->v_W.x(), moved->v_W.y());
    // The body's heading off the top's axes (mod a quarter turn), what a touch-down scores too.
    const auto quarter_deg = [](double a_rad) {
      return std::remainder(a_rad, M_PI / 2) * 180 / M_PI;
    };
    if (moved && pose)  // the body's offset from the top's centre, what a touch-down scores
      std::printf(" body off(%+.3f %+.3f) yaw %+.1f", pose->p_W_B.x() - moved->top_center_W.x(),
                  pose->p_W_B.y() - moved->top_center_W.y(),
                  quarter_deg(yaw_of(pose->q_WB.toRotationMatrix()) - moved->yaw_rad));
    // The reference's baseline and age (the top's parallax falls with the baseline).
    std::printf(" b %.3f age %.2f tr %d%s", r.baseline_m,
                r.ref_utime > 0 ? (f.utime - r.ref_utime) * 1e-6 : -1.0, r.n_tracked,
                r.ref_held ? " held" : "");
    if (r.found() || vision::located_only(r.reason)) {
      const Vector3d e = r.target.p_W - P.top_center_W;
      std::printf(" dC(%+.3f %+.3f %+.3f) size %.3f x %.3f (%+.3f %+.3f) dh %+.3f base %.2f", e.x(),
                  e.y(), e.z(), r.target.size_m[0], r.target.size_m[1],
                  r.target.size_m[0] - P.size_m.x(), r.target.size_m[1] - P.size_m.y(),
                  r.target.height_m - P.size_m.z(), r.baseline_m);
      // Motion capture's camera motion reference -> current against the truth's: its translation
      // error [mm] and rotation error [deg].
      const auto a = cams.find(r.ref_utime), b = cams.find(f.utime);
      if (a != cams.end() && b != cams.end()) {
        const Isometry3d m_mocap = a->second.first.inverse() * b->second.first;
        const Isometry3d m_true = a->second.second.inverse() * b->second.second;
        const Isometry3d d = m_true.inverse() * m_mocap;
        std::printf(" mocap motion err %.1f mm %.3f deg", 1e3 * d.translation().norm(),
                    Eigen::AngleAxisd(d.linear()).angle() * 180 / M_PI);
      }
    }
    if (!shadow_prior.empty()) {
      const auto q = shadow.process(f.pixels, f.utime, pose, f.exposure_s, f.line_delay_s);
      std::printf(" | shadow %s in %d/%d", vision::to_string(q.reason), q.target.n_inliers_target,
                  q.target.n_inliers_dominant);
      if (q.found()) {
        const Vector3d e = q.target.p_W - P.top_center_W;
        std::printf(" dC(%+.3f %+.3f %+.3f) size %.3f x %.3f", e.x(), e.y(), e.z(),
                    q.target.size_m[0], q.target.size_m[1]);
      }
    }
    if (r.moving) {  // the moving top (VISION_PLATFORM)
      const auto& m = *r.moving;
      std::printf(" | moving %s%s cand %d in %d ncc still %.2f moving %.2f size %.2f x %.2f",
                  vision::to_string(m.reason),
                  m.found() && m.cut ? " cut" : (m.found() && m.edges ? " edges" : ""),
                  m.n_candidates, m.n_inliers, m.ncc_still, m.ncc_moving, m.size_m[0], m.size_m[1]);
      if (m.found())
        std::printf(" p(%+.3f %+.3f %.3f) v(%+.3f %+.3f %+.3f) yaw %+.1f sd %.1f rate %+.1f deg/s",
                    m.p_W.x(), m.p_W.y(), m.p_W.z(), m.v_W.x(), m.v_W.y(), m.v_W.z(),
                    m.yaw_rad * 180 / M_PI, std::sqrt(m.var_yaw) * 180 / M_PI,
                    m.yaw_rate_rps * 180 / M_PI);
      if (m.found() && moved)  // against the truth at the frame's time
        std::printf(" err p(%+.3f %+.3f) v(%+.3f %+.3f) yaw %+.1f",
                    m.p_W.x() - moved->top_center_W.x(), m.p_W.y() - moved->top_center_W.y(),
                    m.v_W.x() - moved->v_W.x(), m.v_W.y() - moved->v_W.y(),
                    quarter_deg(m.yaw_rad - moved->yaw_rad));
    }
    std::printf(
        " | filter fused %d run %d refused %d believed %d (gate %d order %d size %d reach %d)",
        filter.fused, filter.run, filter.refused, filter.believed ? 1 : 0, filter.gate,
        filter.order, filter.size, filter.reach);
    if (filter.copy)
      std::printf(" partial %d other tops %d whole %.2f x %.2f top dh %+.3f sd %.3f",
                  filter.copy->n_partial(), filter.copy->n_other_tops(),
                  filter.copy->whole_top().x(), filter.copy->whole_top().y(),
                  filter.copy->top_height().dh_m, std::sqrt(filter.copy->top_height().var_m2));
    // What autonomy follows: the filter's prediction at this frame's time (before the frame)
    // against the truth.
    if (filter.copy && filter.copy->initialised() && moved) {
      const auto pr = filter.copy->predict(f.utime);
      std::printf(" pred err (%+.3f %+.3f) sd %.3f v(%+.2f %+.2f) a(%+.2f %+.2f) yaw %+.1f",
                  pr.p_W.x() - moved->top_center_W.x(), pr.p_W.y() - moved->top_center_W.y(),
                  std::sqrt(std::max(pr.cov_p(0, 0), pr.cov_p(1, 1))), pr.v_W.x(), pr.v_W.y(),
                  pr.a_W.x(), pr.a_W.y(), quarter_deg(pr.yaw_rad - moved->yaw_rad));
    }
    platform = vision::to_platform_msg(r);
    std::printf("%s", flow_note.c_str());
    // Each flow motion against the truth: the camera's motion over the floor and relative to the
    // top, each over its plane's distance (how far off, as a speed over the floor, m/s).
    if (flow_sample && moved) {
      const auto a = truth_cams.find(flow_sample->utime_from);
      const auto b = truth_cams.find(flow_sample->utime_to);
      if (a != truth_cams.end() && b != truth_cams.end()) {
        const double dt = (flow_sample->utime_to - flow_sample->utime_from) * 1e-6;
        const Isometry3d& X1 = a->second;
        const double d = X1.translation().z();
        const Vector3d dp = b->second.translation() - X1.translation();
        const Matrix3d R_C1W = X1.linear().transpose();
        const Vector3d floor_td = R_C1W * dp / d;
        const Vector3d top_td = R_C1W * (dp - moved->v_W * dt) / (d - moved->top_center_W.z());
        const auto off = [&](const Vector3d& td, const Vector3d& truth) {
          return (td - truth).norm() * d / dt;
        };
        std::printf(" | vs floor/top %.2f/%.2f", off(flow_sample->t_over_d_C1, floor_td),
                    off(flow_sample->t_over_d_C1, top_td));
        for (const auto& m : flow_sample->others)
          std::printf(" other %.2f/%.2f", off(m.t_over_d_C1, floor_td), off(m.t_over_d_C1, top_td));
      }
    }
    std::printf("\n");
    if (!dump.empty() && n % every == 0) {
      cv::Mat bgr;
      cv::cvtColor(f.pixels, bgr, cv::COLOR_GRAY2BGR);
      if (truth_px.size() == 4) cv::polylines(bgr, truth_px, true, {0, 255, 0});
      std::vector<cv::Point> o;
      for (const auto& q : r.target.outline)
        o.emplace_back(static_cast<int>(q.x()), static_cast<int>(q.y()));
      if (o.size() == 4) cv::polylines(bgr, o, true, {0, 0, 255});
      for (size_t i = 0; i < r.matched_px.size() && i < r.labels.size(); ++i) {
        const cv::Scalar colour = r.labels[i] == vision::Label::kTarget ? cv::Scalar(0, 0, 255)
                                  : r.labels[i] == vision::Label::kDominant
                                      ? cv::Scalar(255, 0, 0)
                                      : cv::Scalar(0, 255, 255);
        cv::circle(bgr, cv::Point(r.matched_px[i].x(), r.matched_px[i].y()), 2, colour, -1);
      }
      for (const auto& u : r.moving_px)  // the moving top's set
        cv::drawMarker(bgr, cv::Point(u.x(), u.y()), {255, 0, 255}, cv::MARKER_CROSS, 5);
      char name[64];
      std::snprintf(name, sizeof name, "/f%05d.png", n);
      if (!cv::imwrite(dump + name, bgr))
        std::fprintf(stderr, "alight_landing_diag: cannot write %s%s\n", dump.c_str(), name);
    }
    ++n;
    return from_msg(vision::to_msg(r));
  };
  cfg.camera_platform = [&]() -> std::optional<PlatformMeasurement> {
    if (!platform) return std::nullopt;
    std::string why;
    auto m = platform_from_msg(*platform, &why);
    platform.reset();
    return m;
  };
  const auto r = fly_closed_loop(cfg);
  std::printf("# result %s: %s landed %d touchdown %.3f est err %.3f retries %d\n",
              phase_name(r.phase), r.reason.c_str(), r.landed, r.touchdown_error_m,
              r.estimate_error_W.norm(), r.retries);
  for (const auto& why : r.retry_reasons) std::printf("#   retry: %s\n", why.c_str());
  return 0;
} catch (const alight::ParamError& e) {
  // A bad scenario or vehicle file: the message names the file, the key and the value.
  std::fprintf(stderr, "alight_landing_diag: configuration error: %s\n", e.what());
  return 2;
}
