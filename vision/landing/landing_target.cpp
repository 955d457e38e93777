// Landing target, paper 3.2: planes -> gates -> extent (see landing_target.hpp).
#include "vision/landing/landing_target.hpp"

#include <utility>

#include "vision/geometry/waypoint.hpp"
#include "vision/landing/outline.hpp"
#include "vision/landing/rim.hpp"

namespace alight::vision {
namespace {

TargetOutcome refuse(TargetOutcome out, Reason reason) {
  out.reason = reason;
  return out;
}

// The platform on the planes of one source: the gates on the planes, the top's features on its
// plane, the level gate, the features' rectangle and its measurement, the height gate, the cut
// by the border, the photometric gate, then on a top seen whole the extent out to its rims (or
// the top seen running on past a side, located only). Each refusal is the first that applies,
// in that order; `out` carries the labels of the source's first plane and its counts.
TargetOutcome platform_of(const Correspondences& c, const PipelineParams& params,
                          const LandingPlanes& planes, TargetOutcome out, const cv::Mat& gray_1,
                          const cv::Mat& gray_2) {
  const Matrix3d K = c.camera->K();
  const Matrix3d K_inv = K.inverse();
  const Matrix3d H_top_px = K * planes.top.homography() * K_inv;
  const Matrix3d H_floor_px = K * planes.floor.homography() * K_inv;
  const MocapMotion mocap = mocap_motion(c.pose_1, c.pose_2, *c.mount);
  for (size_t i = 0; i < c.size(); ++i)
    out.labels[i] = planes.top_in[i]     ? Label::kTarget
                    : planes.floor_in[i] ? Label::kDominant
                                         : Label::kOutlier;
  out.estimate.n_inliers_dominant = planes.n_floor;
  out.estimate.n_inliers_target = planes.n_top;
  if (const Reason r = plane_gates(c, planes, H_top_px, H_floor_px, mocap.baseline_m, params);
      r != Reason::kOk)
    return refuse(std::move(out), r);

  const Isometry3d X_WC2 = camera_in_world(c.pose_2.X_WB(), c.mount->X_BC());
  const std::vector<Vector3d> pts_W =
      top_points_W(c, planes, H_top_px, X_WC2, mocap.baseline_m, params);
  const Vector3d n_W = top_normal_W(planes, X_WC2);
  if (!top_level(n_W, params.landing)) return refuse(std::move(out), Reason::kTopTilted);
  const auto features = top_features_rect(pts_W, n_W);
  if (!features) return refuse(std::move(out), features.reason());
  const TopRect widened = widened_by_shortfall(*features, pts_W.size());
  if (const Reason r = measure_top(c, planes, widened, X_WC2, params, &out.estimate);
      r != Reason::kOk)
    return refuse(std::move(out), r);
  if (!height_in_range(out.estimate.height_m, params.landing))
    return refuse(std::move(out), Reason::kHeightOutOfRange);
  const bool cut = cut_by_border(c, planes, params.landing);
  const bool images = !gray_1.empty() && !gray_2.empty();
  if (images)
    if (const Reason r = photometric_gate(c, planes, H_floor_px, H_top_px, gray_1, gray_2);
        r != Reason::kOk)
      return refuse(std::move(out), r);
  // A top alone (no floor matches in sight) is seen whole where its features stop short of both
  // images' borders, as any top; close over it, it fills the view and is cut. A top reaching into
  // the epipole's parallax gap is seen in part too: located, its centre not measured.
  const bool gap = !top_clear_of_epipole(c, planes.top_in, H_floor_px, H_top_px, mocap,
                                         params.homography.threshold_px);
  out.reason = cut ? Reason::kPartialView : gap ? Reason::kTopParallaxGap : Reason::kOk;
  // The top's rim, on a top seen whole (a cut top's size is never used): where the rims give no
  // estimate (a waypoint fails, the height leaves its range), the features' stands.
  if (out.reason == Reason::kOk && images) {
    bool runs_on = false;
    if (const auto rim = rim_rect(c, gray_1, gray_2, planes, X_WC2, pts_W, *features, widened,
                                  kTopEndSearchM, &runs_on)) {
      TargetEstimate at_rim = out.estimate;
      if (measure_top(c, planes, *rim, X_WC2, params, &at_rim) == Reason::kOk &&
          at_rim.height_m >= params.landing.min_height_m &&
          at_rim.height_m <= params.landing.max_height_m)
        out.estimate = at_rim;
    }
    // A top running on past a side of its features is in sight, its extent there unseen.
    if (runs_on) out.reason = Reason::kTopRunsOn;
  }
  return out;
}

bool found_or_partial(const TargetOutcome& o) {
  return o.reason == Reason::kOk || located_only(o.reason);
}

}  // namespace

TargetOutcome find_landing_target(const Correspondences& c, const PipelineParams& params,
                                  const cv::Mat& gray_1, const cv::Mat& gray_2,
                                  const PlainRegions* regions_2) {
  assert(c.camera && c.mount);
  const auto usable = [&](const cv::Mat& m) {
    return !m.empty() && m.type() == CV_8UC1 && m.cols == c.camera->width &&
           m.rows == c.camera->height;
  };
  if ((!gray_1.empty() || !gray_2.empty()) && !(usable(gray_1) && usable(gray_2)))
    return find_landing_target(c, params);
  TargetOutcome out;
  out.labels.assign(c.size(), Label::kOutlier);
  const std::string& mode = params.landing.floor_prior;
  TargetOutcome paper = out;
  if (mode != "always") {
    const auto planes = paper_planes(c, params, &paper);
    bool floor_known = false;
    if (!planes) {
      paper.reason = planes.reason();
    } else {
      paper = platform_of(c, params, *planes, paper, gray_1, gray_2);
      floor_known = floor_agrees(planes->floor, c, params);
    }
    if (mode == "off" || (found_or_partial(paper) && floor_known)) return paper;
  }
  // The paper's planes gave no platform, or their floor is not the floor: the known floor's turn.
  TargetOutcome known = out;
  if (const auto planes = known_floor_planes(c, params)) {
    known = platform_of(c, params, *planes, out, gray_1, gray_2);
  } else {
    known.reason = planes.reason();
  }
  // Where the prior finds nothing either, the paper's outcome stands (a floor a few percent off
  // is the paper's bas-relief ambiguity, not a false platform).
  TargetOutcome result = mode == "always" || found_or_partial(known) ? known : paper;
  // One plane in view, the floor's: a top without features of its own is measured by its
  // outline (outline.hpp) on the known floor.
  if (no_top_plane(result.reason) && !gray_1.empty())
    if (auto outline = find_outline_top(c, result.labels, gray_1, gray_2, params, regions_2)) {
      outline->labels = std::move(result.labels);
      outline->estimate.n_inliers_dominant = result.estimate.n_inliers_dominant;
      return *outline;
    }
  return result;
}

}  // namespace alight::vision
