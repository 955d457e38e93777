#pragma once
// Landing, a top without features found by its outline (beyond the paper).
//
// The paper (Brockers et al., SPIE 2011, 3.2) finds the top as the second plane of the matched
// features, and its Fig. 6b notes that features fall short of a featureless region. A top with
// almost no texture of its own (a slate, a painted board, a dim top whose grain is under the
// sensor's noise) gives no features at all: the planes find one plane, the floor's, and the
// frame is refused kNoTargetPlane though the top is plain to see as a region of one grey level
// with a sharp outline. Here, after the planes found no top:
//
//   1. candidates: maximally stable extremal regions (Matas et al., BMVC 2002, OpenCV's MSER)
//      of the image's local texture at a quarter of its resolution (the grey level's standard
//      deviation about each 4 x 4 block over a Gaussian window of one block, so that a grain
//      larger than a block counts): the stage runs only where the floor gave its features, so the
//      floor is busy and a top without features is a plain region of it, whether or not its mean
//      grey stands out from the floor's grains. Only the regions plainer than around them (the
//      map's dark ones) are sought: one busier than around it is texture, the features' to see,
//      and its pixels were most of the cost of MSER's other pass. Those that fill the rectangle
//      along their outline's direction (the mean of four times its normals' angle, which a square
//      has as a longer rectangle does) with the sides of their second moments along it (a level top
//      under a camera looking down is a rectangle in the image) and clear the border. A region the
//      border cuts, or a box seen from aside whose side faces and shadow widen its region past a
//      rectangle, is left to later frames: located from the sides such a region shows, over a busy
//      floor, it was as often a chance region as the top;
//   2. featureless: fewer than min_platform_inliers of the frame's matches inside it (a top
//      with features is the planes' to find or to refuse, never this stage's);
//   3. edges: each side refined at full resolution to the line through the strongest step of
//      grey level across it, the corners where adjacent lines meet; an outline narrower than
//      a top to land on can be from the search height (kMinSidePx) is a stroke of the floor's
//      pattern, not measured;
//   4. height, side by side (h up to max_height_m, or as far as the reference can show the
//      side: height_search_range): the plane z = floor_z_m + h that carries the side onto the
//      reference image (motion capture's poses: camera 2's rays intersected with the plane,
//      projected into camera 1). The step across the side, read in the reference at the carried
//      points, is there only near the right plane (the inner side is the same top, the outer
//      the floor seen through parallax); about it, the reference's own rim is fitted as a line
//      and each point's height is where its plane carries it onto that line. A side along the
//      camera's motion moves along itself and tells nothing (kMinSideParallaxPx), nor does one
//      whose step is too faint or repeats across it (a dark floor beside a dark top): they are
//      left out. The top's
//      height is that of the largest set of sides that agree (kAgreePx); a side below it is on
//      a side face: a face darker than the top (lit from above) belongs to a dark top's region,
//      so that side of the outline is the face's foot, or between foot and rim where the face
//      is narrow;
//   5. the top: each side's line at its own height lies over the rim (a side face stands
//      vertical), and where adjacent lines meet are the top's corners: its centre, sides and
//      heading, as the features' rectangle gives them (extent.hpp). A top narrower than the
//      vehicle's gear (gear_footprint_m) is none to land on: a patch of a coarse floor's pattern
//      placed above it by chance, or a top too small [kTopTooSmall];
//   6. a print, not the top: a plain panel printed on a larger top (a photograph's dark square)
//      has an outline at the top's height too. Where a match beyond the outline (clear of the
//      band of a side face next to the rim, within the outline's size) is carried onto its
//      reference pixel by the plane at that height and not by the floor's, or where the image
//      just beyond a side (past that band) moves with the plane at that height rather than the
//      floor's (a rim's outside is the floor, a print's the top), the top runs on past the
//      outline: located, its extent unseen [kTopRunsOn].
//
// A mark or a shadow on the floor is such a region too; its outline moves with the floor (h
// under min_height_m: kOutlineOnFloor). An outline the reference does not show at any height
// (an edge of light, a reflection, a region the reference's view does not hold) is refused
// kOutlineUnmatched.

#include <functional>
#include <opencv2/core.hpp>
#include <optional>
#include <utility>
#include <vector>

#include "vision/params.hpp"
#include "vision/target.hpp"

namespace alight::vision {

/// A featureless region's outline in the current image: four raw pixels, in order around it.
struct Outline {
  std::vector<Vector2d> corners;
  bool dark = true;  ///< the region darker than what surrounds it
};

/// The sides of an outline must read, in the reference, at least this share of the step across
/// them in the current image at the height found: the inner side is the same top in both, the
/// outer is the floor seen through parallax, of the same mean grey.
constexpr double kMinOutlineAgreement = 0.5;

/// A side above the floor must read this much more of its step at its height than at the
/// floor's plane: a top's rim carried by the floor's plane lands a few pixels beside itself and
/// reads little of it; a busy floor's chance agreement is about as large at any height.
constexpr double kMinOutlineContrast = 0.5;

/// A side counts for the height where the plane at the height found and the floor put its middle
/// this far apart across it in the reference: the step is read 2 px either side of the rim, so
/// a shift under twice that leaves it in reach of the floor's hypothesis.
constexpr double kMinSideParallaxPx = 4.0;

/// Two sides' heights agree where they differ by under this much of their own parallax [px]:
/// a rim fitted over a side's points lies within a few tenths of a pixel.
constexpr double kAgreePx = 1.5;

/// The heights a side's plane is searched over (stage 4): from the floor up to max_h, or up to
/// where the side's parallax across itself between the floor and the plane (parallax_px(h)
/// [px], growing with h as the plane nears the cameras) reaches the reference's diagonal
/// diag_px, whichever is lower; (that height, the parallax there). Below a reference camera only
/// a little above the floor plus max_h, the parallax grows without bound and the search's grid
/// (a step per 2 px of it) with it, for planes that carry the side out of the reference: the
/// frame's time would follow the camera's height, not the image. Bisected, to 2^-40 of max_h.
std::pair<double, double> height_search_range(const std::function<double(double)>& parallax_px,
                                              double max_h, double diag_px);

/// The means of the grey level and of its square over each 4 x 4 block of gray (CV_8UC1) as
/// float images of size `small` (the texture map's, a quarter of the resolution): to the bit what
/// cv::resize with INTER_AREA gives of the image and of its square as floats, summed in integers
/// where the image is four times `small` (any other size: that resize itself).
void block_means(const cv::Mat& gray, const cv::Size& small, cv::Mat* mean, cv::Mat* mean_sq);

/// The most candidates measured per frame (the largest): a top is one region, the rest of a
/// frame's candidates are the floor's patches.
constexpr size_t kMaxOutlines = 2;

/// Stage 1's maximally stable regions of one image (CV_8UC1, raw) and what the image alone says
/// of each (its rectangle, stage 3's refined outline): found on first use and kept, so that the
/// still landing's outline stage and the moving top's (each with its own matches) read one
/// frame's at the cost of one texture map, one MSER and one refinement a region.
class PlainRegions {
 public:
  struct Found {
    cv::Size small;  ///< the texture map's size (a quarter of the resolution)
    std::vector<std::vector<cv::Point>> regions;
    std::vector<cv::Rect> boxes;
    std::vector<size_t> largest_first;  ///< indices into regions
  };
  explicit PlainRegions(cv::Mat gray) : gray_(std::move(gray)) {}
  const cv::Mat& image() const { return gray_; }
  /// Empty for an image too small or not CV_8UC1.
  const Found& found() const;
  /// Region i's rectangle (stage 1) in the image's raw pixels; nullopt for a region that is no
  /// rectangle's.
  const std::optional<std::vector<Vector2d>>& quad(size_t i) const;
  /// Region i's outline refined at full resolution (stage 3) with its shading; nullopt where it
  /// has no rectangle, a side finds no line or the outline is narrower than a top.
  const std::optional<Outline>& outline(size_t i) const;

 private:
  struct Memo {
    std::optional<std::optional<std::vector<Vector2d>>> quad;
    std::optional<std::optional<Outline>> outline;
  };
  cv::Mat gray_;
  mutable std::optional<Found> found_;
  mutable std::vector<Memo> memo_;  // one per region, once found_ is
};

/// Stage 1 and 2: the featureless rectangular regions of the image (regions.image(), the
/// current raw image) with fewer than min_platform_inliers of c's current pixels (u2) inside,
/// largest first, at most max_outlines; each already refined (stage 3).
std::vector<Outline> featureless_outlines(const PlainRegions& regions, const Correspondences& c,
                                          const PipelineParams& params,
                                          size_t max_outlines = kMaxOutlines);
/// The same on an image whose regions nobody keeps.
std::vector<Outline> featureless_outlines(const cv::Mat& gray, const Correspondences& c,
                                          const PipelineParams& params,
                                          size_t max_outlines = kMaxOutlines);

/// Stages 4 and 5 on one outline: the top measured from its outline between the reference
/// (gray_1) and the current image (gray_2), or why not: kOutlineUnmatched (a side with parallax
/// whose step the reference shows at no height), kOutlineSilent (no side tells a height: each
/// steps too faintly, is a line or repeats), kOutlineOnFloor (no side above min_height_m),
/// kSmallBaseline (fewer than two sides with parallax, or no rim among them),
/// kHeightOutOfRange, kCornerOffPlane (a corner's ray misses its plane); kPartialView for a
/// corner within edge_margin_px of the border, kTopRunsOn for a top running on past the outline
/// (stage 6; both located, not measured); kTopTooSmall (its estimate kept) for a top narrower
/// than the gear.
TargetOutcome top_of_outline(const Outline& o, const Correspondences& c, const cv::Mat& gray_1,
                             const cv::Mat& gray_2, const PipelineParams& params);

/// A region whose corners are the floor's own features (within kCornerFeaturePx of a match the
/// planes took for the floor, at two corners or more) is a pattern of the floor: a tile, a
/// slab, a painted rectangle, whose corners the detector finds on the floor's plane. A top's
/// corners stand off that plane. The count of such corners; labels: one per match of c.
constexpr double kCornerFeaturePx = 6.0;
int corners_on_floor(const Outline& o, const Correspondences& c, const std::vector<Label>& labels);

/// The stage as find_landing_target calls it after the planes found no top (labels: theirs, one
/// per match): the first outline (featureless_outlines) measured as a top or located in part,
/// else the first refusal (kOutlineOnFloor for one whose corners are the floor's, as
/// corners_on_floor); nullopt where no featureless outline is in view. regions_2: gray_2's
/// regions where the caller keeps them (the same pixels), else found here.
std::optional<TargetOutcome> find_outline_top(const Correspondences& c,
                                              const std::vector<Label>& labels,
                                              const cv::Mat& gray_1, const cv::Mat& gray_2,
                                              const PipelineParams& params,
                                              const PlainRegions* regions_2 = nullptr);

}  // namespace alight::vision
