#pragma once
// Landing, the extent out to the top's rims (beyond the paper; stage 3, after extent.hpp).
//
// The paper (Brockers et al., SPIE 2011, 3.2) finds the top's plane and its centre from the
// top's features and measures no size; its Fig. 6b notes that features alone fall short of a
// featureless region's true size, which is what a nearly blank top does: its extent falls short
// by more than side_from_extent restores. Given both images, each side of the extent of a top
// seen whole (a cut top's size is never used) is searched outward in the top's plane
// (5 cm) for the top's rim: the mean grey level along lines parallel to the side, at
// offsets from it, read in the current image and in the reference at the same points of the
// top's plane (the top's homography: the plane-induced comparison of Irani & Anandan, ECCV
// 1996, as in warp_diff.hpp, but only along the lines searched). The rim is the first step
// outward that darkens (the top is lit as the floor is and the side faces, turned from the
// light, less; a top darker than what lies beyond keeps its features' extent) and stays dark to
// the search's end (a row of print on the top darkens and brightens again), and the reference
// must show it within a pixel and a half on the top's plane: the rim lies on the plane,
// while an edge of the floor or of a side face beyond moves differently between the views. The
// features' rectangle can be turned from the top's edges, and a line across a turned rim
// spreads its step: the rim's turn (at most 15 deg) is the straight line through the
// steps of short stretches of the side, and the lines are read along it. Rims that agree on a
// turn turn the rectangle onto them (a rim whose stretches gave no turn was read unturned and
// says nothing about it), and each side without a rim is searched again along the turned
// axes: the far end of a side turned from the features' lies beyond the first search's reach,
// and its stretches then gave no turn either. A side without a rim keeps the features' extent and
// its half of side_from_extent's widening (never wider than the evidence shows); with one, the side
// ends at the rim. The plane check (gates.hpp) reads the features' hull, not the rim's
// rectangle: the rim is measured only on a top the check accepts.
//
// The top's end: over a busy floor the mean grey beyond a rim need not step at all (a pale
// margin of print against a patterned floor, a photograph's mid-grey against a circuit board).
// A side without a rim step is then searched outward (kTopEndSearchM) for where the top's
// homography stops explaining the two images: at each offset, the share of the pixels whose
// grey differs between the views, read at the same point of the top's plane, by more than a
// threshold (kTopEndMinDiff, and twice the top's own differences just inside the side). On
// the top that share is near zero, whatever its texture; on a textured floor, which lies off the
// top's plane, it is large. The end is where it steps up (by kTopEndMinRise) in most stretches
// of the side along one straight line, the line's turn read as the rim's. Where the floor beyond
// is flat, the top's homography explains it too and the step lies wherever the floor's texture
// begins: an upper bound, not the rim. So an end counts only where the share stays up over the
// 30 pixels beyond it (a busy floor, not the band that the edge of a rug moves by between the
// views) and where the floor's homography explains most of what the top's does not; a flat band
// of floor that ends along a straight line parallel to the side still passes, and would widen
// the top by the band.
//
// A top running on past its features: a large top's print can give features over a band of it
// only (a photograph's smooth areas, blurred lettering), its edges well past the band or past
// the image's border. Past such a side the end search's pixels that have texture follow the
// top's plane, not the floor's; past a true edge over a busy floor they follow the floor's, and
// a smooth floor tells neither way (the side then stands where the features put it). A side the
// top runs on past is walked outward and read again until a rim or an end past which the top
// does not run on, stepping over smooth stretches past which the top shows again (bare print
// between rows); a walk that leaves the view while the top runs on reports it (the top is
// located, not measured: its extent there is unseen).

#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "vision/landing/extent.hpp"

namespace alight::vision {

/// How far beyond the features a side without a rim step is searched for the top's end [m]: the
/// features fall short of a side by their shortfall (a few centimetres) and by a print's bare
/// margin or band (several more), a third of a 28 cm top's width in all; farther out, the floor
/// read beyond the end lies ever farther from the features the top's plane was fitted on.
constexpr double kTopEndSearchM = 0.1;

/// The top out to its rims: each side of the features' extent (`features`, their points pts_W)
/// moved to its rim where both images show one (else to the top's end within end_search_m of the
/// side: find_landing_target passes kTopEndSearchM; 0, no end search; a side the top runs on
/// past walked out to its rim, its end or as far as the top is seen), else widened as
/// `widened`; nullopt where no side has either. Two or more rims whose measured turns agree turn
/// the rectangle onto them, each side with a rim then where its rim crosses the middle of the
/// stretch read, and each side without one searched again along the turned axes.
/// gray_1 / gray_2: the reference and current raw images. *runs_on (optional): whether the top
/// runs on past a side out of the view (or beyond the walk's reach): its extent there unseen.
std::optional<TopRect> rim_rect(const Correspondences& c, const cv::Mat& gray_1,
                                const cv::Mat& gray_2, const LandingPlanes& planes,
                                const Isometry3d& X_WC2, const std::vector<Vector3d>& pts_W,
                                const TopRect& features, const TopRect& widened,
                                double end_search_m, bool* runs_on = nullptr);

}  // namespace alight::vision
