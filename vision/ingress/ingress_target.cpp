// Ingress target, paper 3.3: wall -> blocks -> faces -> opening (see ingress_target.hpp).
#include "vision/ingress/ingress_target.hpp"

#include <cassert>
#include <utility>

#include "vision/geometry/homography.hpp"
#include "vision/geometry/plane_gain.hpp"
#include "vision/geometry/waypoint.hpp"
#include "vision/ingress/blocks.hpp"
#include "vision/ingress/opening.hpp"
#include "vision/ingress/wall.hpp"

namespace alight::vision {
namespace {

// The current smoothed view at the reference's photometry on the wall (plane_gain.hpp), so that
// the off-wall mask and the faces difference parallax rather than the lens's falloff. The view
// as it is where the wall's inliers set no gain.
cv::Mat at_wall_photometry(const Correspondences& c, const HomographyFit& fit, cv::Size size,
                           const cv::Mat& image_parallax, const cv::Mat& reference_parallax) {
  if (image_parallax.empty() || reference_parallax.empty()) return image_parallax;
  std::vector<Vector2d> wall_px;
  for (size_t k = 0; k < c.size(); ++k)
    if (fit.inlier[k]) wall_px.push_back(c.u2[k]);
  const double scale = static_cast<double>(size.width) / image_parallax.cols;
  const auto gain =
      fit_plane_gain(image_parallax, reference_parallax, scale, fit.H, *c.camera, wall_px);
  return gain ? remove_gain(image_parallax, scale, *c.camera, *gain) : image_parallax;
}

}  // namespace

TargetOutcome find_ingress_target(const Correspondences& c, const cv::Mat& image,
                                  const cv::Mat& reference, const PipelineParams& params) {
  const bool mask = params.ingress.parallax_mask && !reference.empty();
  return find_ingress_target(c, image, mask ? parallax_image(image, params.ingress) : cv::Mat(),
                             mask ? parallax_image(reference, params.ingress) : cv::Mat(), params);
}

namespace {

// Stages 2-4 with `wall` as the wall; the wall's labels and inlier count filled in first.
TargetOutcome find_opening(const Correspondences& c, const Wall& wall,
                           const std::vector<std::optional<Vector3d>>& X_W_match,
                           const cv::Mat& image, const cv::Mat& image_parallax,
                           const cv::Mat& reference_parallax, const PipelineParams& params) {
  const IngressParams& p = params.ingress;
  const HomographyFit& fit = *wall.fit;
  TargetOutcome out;
  out.labels.assign(c.size(), Label::kOutlier);
  const auto refuse = [&](Reason reason) {
    out.reason = reason;
    return std::move(out);
  };
  for (size_t i = 0; i < c.size(); ++i)
    if (fit.inlier[i]) out.labels[i] = Label::kDominant;
  out.estimate.n_inliers_dominant = fit.n_inliers;
  if (!wall.plane) return refuse(wall.plane.reason());

  // 2. The blocks.
  const cv::Mat image_wall_photometry =
      at_wall_photometry(c, fit, image.size(), image_parallax, reference_parallax);
  const Cells cells =
      cut_into_cells(c, fit, image, image_wall_photometry, reference_parallax, p, &out.lines);
  const Block b = best_block(c, fit, cells, p);
  out.estimate.n_inliers_target = b.n_off;
  if (b.n_off < p.min_outliers) return refuse(Reason::kNoOpening);
  for (size_t k = 0; k < c.size(); ++k)
    if (seen_through_wall(c, fit, cells, k)) {
      const int i = cell_of(cells.xc, c.u2[k].x()), j = cell_of(cells.yc, c.u2[k].y());
      if (i >= b.i0 && i < b.i1 && j >= b.j0 && j < b.j1) out.labels[k] = Label::kTarget;
    }

  // 3. The faces: the mask's geometry at full size only.
  OpeningBox box{cells.xc[b.i0], cells.xc[b.i1], cells.yc[b.j0], cells.yc[b.j1]};
  if (!cells.mask.empty() && image_parallax.size() == image.size()) {
    const Matrix3d K = c.camera->K();
    const CutGeometry geometry{Vector2d(K(0, 2), K(1, 2)), wall.depth_m,      *wall.plane, c.camera,
                               image_wall_photometry,      reference_parallax};
    box = to_front_edges(box, cells.mask.size(), geometry);
  }

  // 4. The opening.
  if (const Reason r = measure_opening(c, *wall.plane, box, params, &out.estimate);
      r != Reason::kOk)
    return refuse(r);
  out.reason = opening_checks(c, fit, b, out.labels, X_W_match, out.estimate, p);
  return out;
}

}  // namespace

TargetOutcome find_ingress_target(const Correspondences& c, const cv::Mat& image,
                                  const cv::Mat& image_parallax, const cv::Mat& reference_parallax,
                                  const PipelineParams& params) {
  assert(c.camera && c.mount);
  const auto refuse = [&](Reason reason) {
    TargetOutcome out;
    out.labels.assign(c.size(), Label::kOutlier);
    out.reason = reason;
    return out;
  };
  // 1. The wall.
  const auto planes = fit_two_homographies(c.x1, c.x2, params.homography);
  if (!planes) return refuse(planes.reason());
  if (mocap_motion(c.pose_1, c.pose_2, *c.mount).baseline_m < params.waypoint.min_baseline_m)
    return refuse(Reason::kSmallBaseline);
  const auto X_W_match = triangulate_matches(c, kMaxRayGapPx);
  const Wall wall = choose_wall(c, *planes, X_W_match, params);
  TargetOutcome out =
      find_opening(c, wall, X_W_match, image, image_parallax, reference_parallax, params);
  // Beyond the paper: what is seen through the dominant plane lies in front of it, so it is no
  // wall but the busy room behind a smooth wall's opening; the wall of few features in front of
  // it (wall.hpp) is tried instead, and kept where it finds the opening or a view of part of it.
  if ((out.reason == Reason::kNotBehindWall || out.reason == Reason::kPartialNotBehind) &&
      wall.fit == &planes->first) {
    HomographyFit few_fit;
    if (const auto few =
            few_feature_wall(c, planes->first, wall.depth_m, X_W_match, params, &few_fit)) {
      TargetOutcome other =
          find_opening(c, *few, X_W_match, image, image_parallax, reference_parallax, params);
      if (other.reason == Reason::kOk || located_only(other.reason)) return other;
    }
  }
  return out;
}

}  // namespace alight::vision
