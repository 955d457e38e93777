// Per-frame timing of the vision library's stages at 640x480 on one thread, side by side with
// the OpenCV pipeline a user would pick instead (ORB 1000 + brute-force Hamming with cross check
// + findHomography RANSAC), on the same frames: two views of a floor with a platform on it
// (test/vision/test_images.hpp), true homographies known, so corner accuracy is compared too.
//
//   build-<you>/bin/vision_bench [frames=40] [repeats=3] [max_features=StarParams default]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <random>
#include <string>
#include <vector>

#include "common/heap.hpp"
#include "common/median.hpp"
#include "test/vision/test_images.hpp"
#include "vision/frontend/matcher.hpp"
#include "vision/frontend/star_detector.hpp"
#include "vision/frontend/surf_descriptor.hpp"
#include "vision/geometry/alignment.hpp"
#include "vision/geometry/homography.hpp"
#include "vision/geometry/waypoint.hpp"

using namespace alight;
using namespace alight::vision;
namespace {

/// This thread's CPU time: the machine is shared, and wall time would count other processes.
struct Clock {
  using time_point = double;
  static double now() {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
  }
};
double ms_since(double t0_ms) { return Clock::now() - t0_ms; }

double median(const std::vector<double>& v) { return v.empty() ? 0 : upper_median(v); }

/// Mean corner error of H_est against H_true over the four corners of a rectangle [px].
double rect_error(const Matrix3d& H_est, const Matrix3d& H_true, const cv::Rect& r) {
  Matrix3d T;
  T << 1, 0, r.x, 0, 1, r.y, 0, 0, 1;
  return corner_error(H_est * T, H_true * T, r.width, r.height);
}

struct Stages {
  std::vector<double> detect, describe, match, h1, h2, align, decompose, waypoint, total;
  std::vector<double> track, total_tracked;  // ours: frame-to-frame tracking step
  std::vector<double> h2_single_local, h2_single_plain, h2_single_cv;  // no second plane
  std::vector<double> err_floor, err_top;
  int n_frames = 0, n_floor = 0, n_top = 0, n_aligned = 0, n_waypoint = 0;
  std::vector<double> waypoint_err_m;
};

}  // namespace

int main(int argc, char** argv) {
  // vision_bench [FRAMES [REPEATS]] [--default-heap]: the heap as the nodes set it
  // (retain_freed_memory), or glibc's defaults, under which every frame's large buffers
  // page-fault in again.
  std::vector<std::string> args(argv + 1, argv + argc);
  const auto default_heap = std::find(args.begin(), args.end(), "--default-heap");
  const bool retained = default_heap == args.end();
  if (!retained) args.erase(default_heap);
  if (retained && !retain_freed_memory()) std::fprintf(stderr, "glibc refused the heap settings\n");
  const int frames = args.size() > 0 ? std::atoi(args[0].c_str()) : 40;
  const int repeats = args.size() > 1 ? std::atoi(args[1].c_str()) : 3;
  cv::setNumThreads(1);
  std::mt19937_64 rng(2011);
  std::uniform_real_distribution<double> u(-1, 1);

  StarParams star;
  if (argc > 3) star.max_features = std::atoi(argv[3]);
  SurfParams surf;
  MatchParams match;
  HomographyParams hp;
  AlignParams ap;
  DecompositionParams dp;
  WaypointParams wp;
  CameraMount mount;  // downward, at the body origin
  Stages ours, orb;
  auto orb_detector = cv::ORB::create(1000);
  cv::BFMatcher bf(cv::NORM_HAMMING, true);

  for (int f = 0; f < frames; ++f) {
    const Matrix3d R_21 =
        Eigen::AngleAxisd(3 * M_PI / 180 * u(rng), Vector3d(u(rng), u(rng), u(rng)).normalized())
            .toRotationMatrix();
    const Vector3d t_12 = 0.2 * Vector3d(u(rng), u(rng), 0.2 * u(rng)).normalized();
    const auto scene = testing::two_plane_scene(500 + f, R_21, t_12);
    const Matrix3d K = scene.K, K_inv = K.inverse();
    // Poses consistent with the scene: camera 1 straight down from 1.5 m.
    PoseSample pose_1, pose_2;
    pose_1.p_W_B = Vector3d(0, 0, 1.5);
    const Matrix3d R_WC1 = mount.R_BC, R_WC2 = R_WC1 * R_21.transpose();
    pose_2.p_W_B = pose_1.p_W_B + R_WC1 * t_12;
    pose_2.q_WB = Quaterniond(R_WC2 * mount.R_BC.transpose());
    const Vector2d top_centre_2 =
        (scene.H_top * Vector2d(scene.top_in_1.x + scene.top_in_1.width / 2.0,
                                scene.top_in_1.y + scene.top_in_1.height / 2.0)
                           .homogeneous())
            .hnormalized();
    const Vector3d p_W_true =
        pose_2.p_W_B + R_WC2 * (K_inv * top_centre_2.homogeneous()) *
                           (scene.d_top_m - scene.n_1.dot(t_12));  // depth of the top in cam 2

    // Reference frame features are computed once (as the tracker keeps them), outside timing.
    const cv::Mat ref_int = integral_image(scene.image_1);
    const auto ref_kp = detect_star(scene.image_1, ref_int, star);
    if (!ref_kp) continue;
    const cv::Mat ref_desc = describe_surf(ref_int, *ref_kp, surf);
    const auto ref_sign = response_signs(*ref_kp);
    std::vector<cv::KeyPoint> orb_ref_kp;
    cv::Mat orb_ref_desc;
    orb_detector->detectAndCompute(scene.image_1, cv::noArray(), orb_ref_kp, orb_ref_desc);

    for (int rep = 0; rep < repeats; ++rep) {
      // ---- ours
      auto t0 = Clock::now(), t_all = t0;
      const cv::Mat cur_int = integral_image(scene.image_2);
      const auto kp = detect_star(scene.image_2, cur_int, star);
      ours.detect.push_back(ms_since(t0));
      if (!kp) continue;
      t0 = Clock::now();
      const cv::Mat desc = describe_surf(cur_int, *kp, surf);
      ours.describe.push_back(ms_since(t0));
      t0 = Clock::now();
      const auto sign = response_signs(*kp);
      const auto m = match_descriptors(ref_desc, desc, match, &ref_sign, &sign);
      ours.match.push_back(ms_since(t0));
      std::vector<Vector2d> x1, x2;
      for (const auto& mm : m) {
        x1.emplace_back((*ref_kp)[mm.i1].x, (*ref_kp)[mm.i1].y);
        x2.emplace_back((*kp)[mm.i2].x, (*kp)[mm.i2].y);
      }
      // The tracker's per-frame step (ReferenceTracker::add): match with the previous frame and
      // check against a loose homography. The previous frame is stood in for by the reference.
      const double t_track0 = Clock::now();
      {
        const auto mt = match_descriptors(ref_desc, desc, match, &ref_sign, &sign);
        std::vector<Vector2d> a, b;
        for (const auto& mm : mt) {
          a.emplace_back((*ref_kp)[mm.i1].x, (*ref_kp)[mm.i1].y);
          b.emplace_back((*kp)[mm.i2].x, (*kp)[mm.i2].y);
        }
        HomographyParams loose;
        loose.threshold_px = 8.0;
        loose.refine_iterations = 0;
        (void)fit_homography(a, b, loose);
      }
      const double t_track = ms_since(t_track0);
      ours.track.push_back(t_track);
      t0 = Clock::now();
      const auto fit1 = fit_homography(x1, x2, hp);
      ours.h1.push_back(ms_since(t0));
      if (!fit1) continue;
      std::vector<Vector2d> o1, o2;
      for (size_t i = 0; i < x1.size(); ++i)
        if (!fit1->inlier[i]) o1.push_back(x1[i]), o2.push_back(x2[i]);
      t0 = Clock::now();
      const auto fit2 = fit_homography(o1, o2, hp, Sampling::kLocal);
      ours.h2.push_back(ms_since(t0));
      double t_align = 0, t_dec = 0, t_wp = 0;
      std::optional<PlaneMotion> top_motion;
      auto rays_of = [&](const std::vector<Vector2d>& p, const std::vector<uint8_t>& mask,
                         std::vector<Vector3d>& out) {
        for (size_t i = 0; i < p.size(); ++i)
          if (mask[i]) out.push_back(K_inv * p[i].homogeneous());
      };
      std::vector<Vector3d> r1a, r2a, r1b, r2b;
      rays_of(x1, fit1->inlier, r1a);
      rays_of(x2, fit1->inlier, r2a);
      if (fit2) {
        rays_of(o1, fit2->inlier, r1b);
        rays_of(o2, fit2->inlier, r2b);
        t0 = Clock::now();
        const auto al = align_two_planes(calibrate_homography(fit1->H, K), r1a, r2a,
                                         calibrate_homography(fit2->H, K), r1b, r2b, ap, dp);
        t_align = ms_since(t0);
        if (al) {
          top_motion = al->plane_b();
          if (rep == 0) ++ours.n_aligned;
        }
      }
      // Decomposition alone (the single-plane path with the motion-capture prior).
      t0 = Clock::now();
      DecompositionPrior prior;
      prior.R_21 = mocap_motion(pose_1, pose_2, mount).R_21;
      const auto dec = decompose(calibrate_homography(fit1->H, K), r1a, r2a, prior, dp);
      t_dec = ms_since(t0);
      if (top_motion) {
        t0 = Clock::now();
        const auto w = compute_waypoint(*top_motion, K_inv * top_centre_2.homogeneous(), pose_1,
                                        pose_2, mount, wp);
        t_wp = ms_since(t0);
        if (w && rep == 0) {
          ++ours.n_waypoint;
          ours.waypoint_err_m.push_back((w->p_W - p_W_true).norm());
        }
      }
      ours.align.push_back(t_align);
      ours.decompose.push_back(t_dec);
      ours.waypoint.push_back(t_wp);
      ours.total_tracked.push_back(ms_since(t_all));
      ours.total.push_back(ours.total_tracked.back() - t_track);
      if (rep == 0) {
        ++ours.n_frames;
        ++ours.n_floor;
        ours.err_floor.push_back(corner_error(fit1->H, scene.H_floor, 640, 480));
        if (fit2) {
          ++ours.n_top;
          ours.err_top.push_back(rect_error(fit2->H, scene.H_top, scene.top_in_1));
        }
      }

      // ---- ORB + BFMatcher + findHomography
      t0 = t_all = Clock::now();
      std::vector<cv::KeyPoint> okp;
      cv::Mat odesc;
      orb_detector->detectAndCompute(scene.image_2, cv::noArray(), okp, odesc);
      orb.detect.push_back(ms_since(t0));
      t0 = Clock::now();
      std::vector<cv::DMatch> om;
      bf.match(orb_ref_desc, odesc, om);
      orb.match.push_back(ms_since(t0));
      std::vector<cv::Point2f> p1, p2;
      for (const auto& mm : om)
        p1.push_back(orb_ref_kp[mm.queryIdx].pt), p2.push_back(okp[mm.trainIdx].pt);
      t0 = Clock::now();
      cv::Mat mask;
      const cv::Mat H1 =
          p1.size() >= 4 ? cv::findHomography(p1, p2, cv::RANSAC, 2.0, mask) : cv::Mat();
      orb.h1.push_back(ms_since(t0));
      cv::Mat H2;
      t0 = Clock::now();
      if (!H1.empty()) {
        std::vector<cv::Point2f> q1, q2;
        for (size_t i = 0; i < p1.size(); ++i)
          if (!mask.at<uchar>(int(i))) q1.push_back(p1[i]), q2.push_back(p2[i]);
        cv::Mat mask2;
        if (q1.size() >= 12) H2 = cv::findHomography(q1, q2, cv::RANSAC, 2.0, mask2);
        if (!H2.empty() && cv::countNonZero(mask2) < 12) H2 = cv::Mat();
      }
      orb.h2.push_back(ms_since(t0));
      orb.total.push_back(ms_since(t_all));
      if (rep == 0) {
        ++orb.n_frames;
        if (!H1.empty()) {
          ++orb.n_floor;
          orb.err_floor.push_back(corner_error(testing::from_cv(H1), scene.H_floor, 640, 480));
        }
        if (!H2.empty()) {
          ++orb.n_top;
          orb.err_top.push_back(rect_error(testing::from_cv(H2), scene.H_top, scene.top_in_1));
        }
      }
      (void)dec;
    }

    // One plane only (floor without platform): the second search must give up quickly.
    {
      const cv::Mat floor_1 = testing::procedural_photo(640, 480, 500 + f);
      cv::Mat floor_2;
      cv::warpPerspective(floor_1, floor_2, testing::to_cv(scene.H_floor), cv::Size(640, 480),
                          cv::INTER_LINEAR, cv::BORDER_REFLECT101);
      const cv::Mat i1 = integral_image(floor_1), i2 = integral_image(floor_2);
      const auto k1 = detect_star(floor_1, i1, star), k2 = detect_star(floor_2, i2, star);
      if (!k1 || !k2) continue;
      const auto s1 = response_signs(*k1), s2 = response_signs(*k2);
      const auto m = match_descriptors(describe_surf(i1, *k1, surf), describe_surf(i2, *k2, surf),
                                       match, &s1, &s2);
      std::vector<Vector2d> x1, x2;
      for (const auto& mm : m) {
        x1.emplace_back((*k1)[mm.i1].x, (*k1)[mm.i1].y);
        x2.emplace_back((*k2)[mm.i2].x, (*k2)[mm.i2].y);
      }
      const auto fit1 = fit_homography(x1, x2, hp);
      if (!fit1) continue;
      // Real wrong matches are few on this clean pair: inject 100 random ones, as a textured
      // scene with repetitive structure or motion blur would give.
      std::uniform_real_distribution<double> ux(0, 640), uy(0, 480);
      for (int i = 0; i < 100; ++i) {
        x1.emplace_back(ux(rng), uy(rng));
        x2.emplace_back(ux(rng), uy(rng));
      }
      std::vector<uint8_t> in1 = fit1->inlier;
      in1.resize(x1.size(), 0);
      std::vector<Vector2d> o1, o2;
      std::vector<cv::Point2f> q1, q2;
      for (size_t i = 0; i < x1.size(); ++i)
        if (!in1[i]) {
          o1.push_back(x1[i]), o2.push_back(x2[i]);
          q1.emplace_back(float(x1[i].x()), float(x1[i].y()));
          q2.emplace_back(float(x2[i].x()), float(x2[i].y()));
        }
      for (int rep = 0; rep < repeats; ++rep) {
        double t0 = Clock::now();
        (void)fit_homography(o1, o2, hp, Sampling::kLocal);
        ours.h2_single_local.push_back(ms_since(t0));
        t0 = Clock::now();
        (void)fit_homography(o1, o2, hp, Sampling::kUniform);
        ours.h2_single_plain.push_back(ms_since(t0));
        t0 = Clock::now();
        if (q1.size() >= 4) (void)cv::findHomography(q1, q2, cv::RANSAC, 2.0);
        ours.h2_single_cv.push_back(ms_since(t0));
      }
    }
  }

  std::printf(
      "vision_bench: %d frames x %d repeats, 640x480, 1 thread, %s, median thread-CPU ms "
      "per frame\n",
      frames, repeats,
      retained ? "heap keeps freed memory (as the nodes)" : "glibc's default heap");
  std::printf("%-12s %10s %10s\n", "stage", "ours", "ORB+BF+H");
  auto row = [](const char* name, const std::vector<double>& a, const std::vector<double>* b) {
    if (b)
      std::printf("%-12s %10.3f %10.3f\n", name, median(a), median(*b));
    else
      std::printf("%-12s %10.3f %10s\n", name, median(a), "-");
  };
  row("detect", ours.detect, &orb.detect);
  row("describe", ours.describe, nullptr);
  row("match", ours.match, &orb.match);
  row("first H", ours.h1, &orb.h1);
  row("second H", ours.h2, &orb.h2);
  row("align", ours.align, nullptr);
  row("decompose", ours.decompose, nullptr);
  row("waypoint", ours.waypoint, nullptr);
  row("total", ours.total, &orb.total);
  row("track step", ours.track, nullptr);
  row("total+track", ours.total_tracked, &orb.total);
  std::printf("(ORB's detect column is detectAndCompute: detection and description)\n");
  std::printf(
      "floor H found: ours %d/%d, ORB %d/%d; median floor corner error: ours %.3f px, "
      "ORB %.3f px\n",
      ours.n_floor, ours.n_frames, orb.n_floor, orb.n_frames, median(ours.err_floor),
      median(orb.err_floor));
  std::printf(
      "platform H found: ours %d/%d, ORB %d/%d; median platform-corner error: ours %.3f "
      "px, ORB %.3f px\n",
      ours.n_top, ours.n_frames, orb.n_top, orb.n_frames, median(ours.err_top),
      median(orb.err_top));
  std::printf(
      "one plane only + 100 injected wrong matches, second search: ours (local, early exit) %.3f "
      "ms, ours plain "
      "uniform RANSAC (cap %d) %.3f ms, OpenCV findHomography %.3f ms\n",
      median(ours.h2_single_local), hp.max_iterations, median(ours.h2_single_plain),
      median(ours.h2_single_cv));
  std::printf("aligned %d/%d; waypoint of the platform centre: %d, median error %.4f m\n",
              ours.n_aligned, ours.n_frames, ours.n_waypoint, median(ours.waypoint_err_m));
  return 0;
}
