// Ingress stage 4, the opening (paper 3.1.3, 3.3; see opening.hpp).
#include "vision/ingress/opening.hpp"

#include <algorithm>
#include <cmath>

#include "common/median.hpp"
#include "vision/geometry/waypoint.hpp"

namespace alight::vision {
namespace {

// A partial view's features lie well behind the wall's own features, both triangulated with
// motion capture's poses: a poor homography (few inliers, its plane in front of the wall) leaves
// the wall's own features off it, all "behind" its plane. The median, not a share: an opening's
// inner faces (jambs, sill) lie within the wall's thickness behind it, and at the vantages they
// can hold a third of the block's features. A room seen through lies metres behind, the
// thickest inner faces within 0.3 m: the median lies 0.25 m behind at least.
constexpr double kPartialBehindM = 0.25;
bool partial_behind_wall(const Correspondences& c, const HomographyFit& wall,
                         const std::vector<Label>& labels,
                         const std::vector<std::optional<Vector3d>>& X_W_match,
                         const TargetEstimate& e, const IngressParams& p) {
  auto offset = [&](size_t k) -> std::optional<double> {
    const auto& X_W = X_W_match[k];
    if (!X_W) return std::nullopt;
    return e.n_W.dot(*X_W - e.p_W);
  };
  std::vector<double> wall_offset;
  for (size_t k = 0; k < c.size(); ++k)
    if (wall.inlier[k])
      if (const auto d = offset(k)) wall_offset.push_back(*d);
  std::vector<double> block_offset;
  for (size_t k = 0; k < c.size(); ++k)
    if (labels[k] == Label::kTarget)
      if (const auto d = offset(k)) block_offset.push_back(*d);
  return !(wall_offset.empty() || static_cast<int>(block_offset.size()) < p.min_outliers ||
           upper_median(block_offset) > upper_median(wall_offset) - kPartialBehindM);
}

}  // namespace

// The cut's points taken through the lens are a curve bowing the other way about the edge; the
// straight line fitted to them lies on the edge but for a residual of second order in the
// distortion (the cut is the edge's raw image less its mean bow). The line's own raw image gives
// that residual: the cut is moved by the difference between it and the line's raw mean, and the
// line fitted again (kSideRounds fits in all; a strong barrel lens leaves 0.7-0.9 px after one).
constexpr int kSideSamples = 17;
constexpr int kSideRounds = 3;

namespace {

// A line across = offset + slope * along in normalised coordinates (along: y for a vertical side).
struct SideLine {
  double offset = 0, slope = 0;
};

// The line fitted to the raw segment's points taken through the lens.
SideLine line_through_lens(const CameraModel& camera, const Vector2d& from, const Vector2d& to,
                           bool vertical) {
  double s_a = 0, s_b = 0, s_aa = 0, s_ab = 0;
  for (int i = 0; i < kSideSamples; ++i) {
    const Vector3d r = camera.ray(from + (to - from) * (i / double(kSideSamples - 1)));
    const double along = vertical ? r.y() : r.x(), across = vertical ? r.x() : r.y();
    s_a += along, s_b += across, s_aa += along * along, s_ab += along * across;
  }
  const double n = kSideSamples, det = n * s_aa - s_a * s_a;
  SideLine line;
  line.slope = det > 0 ? (n * s_ab - s_a * s_b) / det : 0.0;
  line.offset = (s_b - line.slope * s_a) / n;
  return line;
}

Vector3d ray_on(const SideLine& line, double along, bool vertical) {
  const double across = line.offset + line.slope * along;
  return vertical ? Vector3d(across, along, 1) : Vector3d(along, across, 1);
}

}  // namespace

Vector2d side_middle(const CameraModel& camera, const Vector2d& from, const Vector2d& to,
                     const Vector2d& centre) {
  const Vector2d plain = from + 0.5 * (to - from);
  if (!camera.has_distortion()) return plain;
  const bool vertical = std::abs(to.y() - from.y()) >= std::abs(to.x() - from.x());
  const int k = vertical ? 0 : 1;  // the raw coordinate across the side
  const Vector3d r_from = camera.ray(from), r_to = camera.ray(to);
  const double along_from = vertical ? r_from.y() : r_from.x();
  const double along_to = vertical ? r_to.y() : r_to.x();
  Vector2d a = from, b = to;
  SideLine line = line_through_lens(camera, a, b, vertical);
  for (int round = 1; round < kSideRounds; ++round) {
    // The line's raw image, across the side, on average along the raw side (as the cut's
    // pixels weigh it: one per raw row or column).
    double sum = 0, length = 0;
    std::optional<Vector2d> last;
    for (int i = 0; i < kSideSamples; ++i) {
      const double t = i / double(kSideSamples - 1);
      const auto px =
          camera.project(ray_on(line, along_from + t * (along_to - along_from), vertical));
      if (!px) return plain;
      if (last) {
        const double step = (*px)(1 - k) - (*last)(1 - k);
        sum += 0.5 * ((*px)(k) + (*last)(k)) * step, length += step;
      }
      last = px;
    }
    if (!(std::abs(length) > 0)) return plain;
    const double shift = 0.5 * (from(k) + to(k)) - sum / length;
    a(k) += shift, b(k) += shift;
    line = line_through_lens(camera, a, b, vertical);
  }
  const Vector3d rc = camera.ray(centre);
  const auto px = camera.project(ray_on(line, vertical ? rc.y() : rc.x(), vertical));
  return px ? *px : plain;
}

Reason measure_opening(const Correspondences& c, const PlaneMotion& wall, const OpeningBox& box,
                       const PipelineParams& params, TargetEstimate* e) {
  const double left = box.left, right = box.right, top = box.top, bottom = box.bottom;
  const Vector2d centre(0.5 * (left + right), 0.5 * (top + bottom));
  auto on_wall = [&](const Vector2d& px) {
    return compute_waypoint(wall, c.ray_of_pixel2(px), c.pose_1, c.pose_2, *c.mount,
                            params.waypoint);
  };
  const CameraModel& cam = *c.camera;
  const auto w_c = on_wall(centre);
  const auto w_l = on_wall(side_middle(cam, {left, top}, {left, bottom}, centre));
  const auto w_r = on_wall(side_middle(cam, {right, top}, {right, bottom}, centre));
  const auto w_t = on_wall(side_middle(cam, {left, top}, {right, top}, centre));
  const auto w_b = on_wall(side_middle(cam, {left, bottom}, {right, bottom}, centre));
  for (const auto* w : {&w_c, &w_l, &w_r, &w_t, &w_b})
    if (!*w) return w->reason();
  e->p_W = w_c->p_W;
  e->n_W = w_c->n_W;
  e->pixel = centre;
  e->size_m[0] = (w_r->p_W - w_l->p_W).norm();
  e->size_m[1] = (w_b->p_W - w_t->p_W).norm();
  e->outline = {{left, top}, {right, top}, {right, bottom}, {left, bottom}};
  const double min_size_m = params.ingress.min_size_m;
  if (e->size_m[0] < min_size_m || e->size_m[1] < min_size_m) return Reason::kOpeningTooSmall;
  return Reason::kOk;
}

Behind behind_the_wall(const Correspondences& c, const HomographyFit& wall,
                       const std::vector<Label>& labels,
                       const std::vector<std::optional<Vector3d>>& X_W_match,
                       const TargetEstimate& e, const IngressParams& p) {
  Behind b;
  for (size_t k = 0; k < c.size(); ++k) {
    const auto& X_W = X_W_match[k];
    if (labels[k] != Label::kTarget || !X_W) continue;
    ++b.in_block;
    if (e.n_W.dot(*X_W - e.p_W) < -p.behind_margin_m) {
      ++b.behind;
      b.parallax_px.push_back((c.x2[k] - (wall.H * c.x1[k].homogeneous()).hnormalized()).norm());
    }
  }
  return b;
}

Reason opening_checks(const Correspondences& c, const HomographyFit& wall, const Block& block,
                      const std::vector<Label>& labels,
                      const std::vector<std::optional<Vector3d>>& X_W_match,
                      const TargetEstimate& e, const IngressParams& p) {
  Behind behind = behind_the_wall(c, wall, labels, X_W_match, e, p);
  if (p.min_behind_share > 0 &&
      (behind.behind < p.min_outliers || behind.behind < p.min_behind_share * behind.in_block))
    return Reason::kNotBehindWall;
  // A block reaching the image border has no cut there: the opening may go on out of view, so
  // its centre and size are not known. It must show what a whole opening shows at one of its
  // corners at least: the wall beyond two of its sides, a hole's concave corner (two adjacent
  // sides) or its two edges in one direction (opposite sides). The space past the wall's end and
  // above its top has the wall beyond neither of its two sides in view.
  const bool cut = block.at_border;
  int framed = 0;
  for (const int n : block.wall_beyond) framed += n >= kWallShownInliers;
  if (cut && framed < 2) return Reason::kPartialNotFramed;
  if (cut && !partial_behind_wall(c, wall, labels, X_W_match, e, p))
    return Reason::kPartialNotBehind;
  if (!cut && p.min_opening_parallax_px > 0) {
    const auto& v = behind.parallax_px;
    if (v.empty() || upper_median(v) < p.min_opening_parallax_px) return Reason::kLowParallax;
  }
  return cut ? Reason::kPartialView : Reason::kOk;
}

}  // namespace alight::vision
