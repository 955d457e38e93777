// Ingress diagnostics: one scene flown in process with the real vision, every frame's
// outcome printed against the simulator's truth: reason, the opening's box in the image against
// the true opening's front-face box projected with the true camera pose, width / height and the
// centre's error, and autonomy's phase. With --dump DIR the frames (and the truth box) are
// written as PNG for a look.
//
//   build/bin/alight_ingress_diag --scenario FILE [--seed N] [--dump DIR] [--every K]

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "autonomy/convert.hpp"
#include "closed_loop.hpp"
#include "common/build_paths.hpp"
#include "common/params.hpp"
#include "sim/params.hpp"
#include "vision/node/convert.hpp"
#include "vision/node/diag_image.hpp"
#include "vision/params.hpp"
#include "vision/pipeline.hpp"

using namespace alight;
using namespace alight::autonomy;
using namespace alight::autonomy::test;

int main(int argc, char** argv) try {
  CLI::App app{"ingress diagnostics: per-frame vision against the truth"};
  std::string scenario_file, dump;
  std::string vehicle = std::string(alight::build::source_dir()) + "/config/vehicles/pelican.yaml";
  uint64_t seed = 1;
  int every = 1;
  app.add_option("--scenario", scenario_file)->required();
  app.add_option("--seed", seed);
  app.add_option("--vehicle", vehicle);
  app.add_option("--dump", dump);
  app.add_option("--every", every);
  CLI11_PARSE(app, argc, argv);
  cv::setNumThreads(1);

  const auto scenario = sim::load_scenario(scenario_file);
  const auto& w = *scenario.wall;
  const Vector3d centre_W(w.x_m, w.center_y_m + w.opening_center_yz_m.x(),
                          w.opening_center_yz_m.y());
  const Vector2d size = w.opening_size_m;
  std::printf("# opening centre (%.3f %.3f %.3f) size %.3f x %.3f thickness %.3f\n", centre_W.x(),
              centre_W.y(), centre_W.z(), size.x(), size.y(), w.thickness_m);
  const auto params = vision::load_node_params(vehicle);
  // The camera as rendered: the vision undistorts with the scenario's lens, as the node does.
  auto rig = sim::load_camera_rig(vehicle, "forward");
  rig.model = sim::with_lens(rig.model, scenario.camera.effects);
  vision::Pipeline pipeline(vision::Mission::kIngress, params.pipeline, rig.model, rig.mount);
  Phase phase = Phase::kIdle;
  ClosedLoopConfig c;
  c.vehicle_file = vehicle;
  c.scenario_file = scenario_file;
  c.mission = Mission::kIngress;
  c.seed = seed;
  // Each change of phase, and of refinement's vantage, as a line of its own: where autonomy sent
  // the vehicle, beside what the vision saw.
  Vector3d vantage = Vector3d::Zero();
  c.script = [&](const Autonomy& a, double t_s, ScriptActions&) {
    const Vector3d v = a.current_vantage();
    if (a.phase() != phase || (v - vantage).norm() > 1e-3)
      std::printf("# %7.3f %s -> %s vantage (%.2f %.2f %.2f)\n", t_s, phase_name(phase),
                  phase_name(a.phase()), v.x(), v.y(), v.z());
    phase = a.phase();
    vantage = v;
  };
  int n = 0;
  c.camera_vision = [&](const sim::CameraFrame& f, const std::optional<PoseSample>& pose) {
    const auto r = pipeline.process(f.pixels, f.utime, pose, f.exposure_s, f.line_delay_s);
    // True box: the front face's corners in the image.
    const Isometry3d X_CW = f.X_WC.inverse();
    double tl = 1e9, tr = -1e9, tt = 1e9, tb = -1e9;
    bool all = true;
    for (int sy : {-1, 1})
      for (int sz : {-1, 1}) {
        const Vector3d p = centre_W + Vector3d(0, sy * size.x() / 2, sz * size.y() / 2);
        const auto px = rig.model.project(X_CW * p);
        if (!px) {
          all = false;
          continue;
        }
        tl = std::min(tl, px->x()), tr = std::max(tr, px->x());
        tt = std::min(tt, px->y()), tb = std::max(tb, px->y());
      }
    // The inner faces' far edges (the wall's back face), where the mask's border sits when the
    // faces look flat (the thickness bias, README).
    double bl = 1e9, br = -1e9, bt = 1e9, bb = -1e9;
    for (int sy : {-1, 1})
      for (int sz : {-1, 1}) {
        const Vector3d p = centre_W + Vector3d(w.thickness_m, sy * size.x() / 2, sz * size.y() / 2);
        if (const auto px = rig.model.project(X_CW * p)) {
          bl = std::min(bl, px->x()), br = std::max(br, px->x());
          bt = std::min(bt, px->y()), bb = std::max(bb, px->y());
        }
      }
    const Vector3d cam = f.X_WC.translation();
    std::printf("%7.3f %-12s cam(%.2f %.2f %.2f) %-16s", (f.utime - 1700000000000000) * 1e-6,
                phase_name(phase), cam.x(), cam.y(), cam.z(), vision::to_string(r.reason));
    std::printf(" truth[%.1f %.1f %.1f %.1f]%s back[%.1f %.1f %.1f %.1f]", tl, tr, tt, tb,
                all ? "" : "?", bl, br, bt, bb);
    if (r.found()) {
      const auto& o = r.target.outline;
      const Vector3d e = r.target.p_W - centre_W;
      // The box's width and height on the true wall plane from the true pose: the box's own
      // error, apart from the estimated plane's depth.
      auto on_wall = [&](double u, double v) {
        const Vector3d d = f.X_WC.linear() * rig.model.ray(Vector2d(u, v));
        return Vector3d(cam + (w.x_m - cam.x()) / d.x() * d);
      };
      const Vector2d mid = r.target.pixel;
      const double box_w = (on_wall(o[1].x(), mid.y()) - on_wall(o[0].x(), mid.y())).norm();
      const double box_h = (on_wall(mid.x(), o[2].y()) - on_wall(mid.x(), o[0].y())).norm();
      std::printf(" box[%.1f %.1f %.1f %.1f] dW %+.3f dH %+.3f dC(%+.3f %+.3f %+.3f) in %d/%d",
                  o[0].x(), o[1].x(), o[0].y(), o[2].y(), r.target.size_m[0] - size.x(),
                  r.target.size_m[1] - size.y(), e.x(), e.y(), e.z(), r.target.n_inliers_target,
                  r.target.n_inliers_dominant);
      std::printf(" boxW %+.3f boxH %+.3f", box_w - size.x(), box_h - size.y());
    } else if (r.reason == vision::Reason::kPartialView) {
      // A partial view reaches autonomy as a first sighting: where it put the target.
      const Vector3d e = r.target.p_W - centre_W;
      std::printf(" sighting dC(%+.3f %+.3f %+.3f) in %d/%d", e.x(), e.y(), e.z(),
                  r.target.n_inliers_target, r.target.n_inliers_dominant);
    } else {
      std::printf(" in %d/%d", r.target.n_inliers_target, r.target.n_inliers_dominant);
    }
    std::printf(" lines %zu base %.2f\n", r.lines.size(), r.baseline_m);
    if (!dump.empty() && n % every == 0) {
      // The node's diagnostic image (matches by label, lines, the found outline), with the true
      // front-face box over it.
      cv::Mat bgr = vision::draw_diag_image(f.pixels, r);
      cv::rectangle(bgr, cv::Point(tl, tt), cv::Point(tr, tb), {255, 0, 255});
      char name[64];
      std::snprintf(name, sizeof name, "/f%05d.png", n);
      cv::imwrite(dump + name, bgr);
      std::snprintf(name, sizeof name, "/raw%05d.png", n);
      cv::imwrite(dump + name, f.pixels);
    }
    ++n;
    return from_msg(vision::to_msg(r));
  };
  const auto r = fly_closed_loop(c);
  const Vector3d& est = r.estimate_error_W;
  std::printf(
      "# result %s: %s crossed %d collided %d offset %.3f est err %.3f (%+.3f %+.3f %+.3f) "
      "retries %d\n",
      phase_name(r.phase), r.reason.c_str(), r.crossed_wall, r.collided, r.max_lateral_in_wall_m,
      est.norm(), est.x(), est.y(), est.z(), r.retries);
  for (const auto& why : r.retry_reasons) std::printf("# retry: %s\n", why.c_str());
  return 0;
} catch (const alight::ParamError& e) {
  // A bad scenario or vehicle file: the message names the file, the key and the value.
  std::fprintf(stderr, "alight_ingress_diag: configuration error: %s\n", e.what());
  return 2;
}
