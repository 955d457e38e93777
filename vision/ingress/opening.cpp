// Ingress stage 4, the opening (paper 3.1.3, 3.3; see opening.hpp).
#include "vision/ingress/opening.hpp"

#include <algorithm>

#include "vision/geometry/waypoint.hpp"

namespace alight::vision {
namespace {

double median(std::vector<double>& v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

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
           median(block_offset) > median(wall_offset) - kPartialBehindM);
}

}  // namespace

Reason measure_opening(const Correspondences& c, const PlaneMotion& wall, const OpeningBox& box,
                       const PipelineParams& params, TargetEstimate* e) {
  const double left = box.left, right = box.right, top = box.top, bottom = box.bottom;
  const Vector2d centre(0.5 * (left + right), 0.5 * (top + bottom));
  auto on_wall = [&](const Vector2d& px) {
    return compute_waypoint(wall, c.ray_of_pixel2(px), c.pose_1, c.pose_2, *c.mount,
                            params.waypoint);
  };
  const auto w_c = on_wall(centre);
  const auto w_l = on_wall({left, centre.y()}), w_r = on_wall({right, centre.y()});
  const auto w_t = on_wall({centre.x(), top}), w_b = on_wall({centre.x(), bottom});
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
    auto& v = behind.parallax_px;
    const auto mid = v.begin() + v.size() / 2;
    if (!v.empty()) std::nth_element(v.begin(), mid, v.end());
    if (v.empty() || *mid < p.min_opening_parallax_px) return Reason::kLowParallax;
  }
  return cut ? Reason::kPartialView : Reason::kOk;
}

}  // namespace alight::vision
