#include "vision/status.hpp"

namespace alight::vision {

const char* to_string(Reason r) {
  switch (r) {
    case Reason::kOk:
      return "ok";
    case Reason::kNoPose:
      return "no pose";
    case Reason::kNoReference:
      return "no reference frame";
    case Reason::kTooFewFeatures:
      return "too few features";
    case Reason::kTooFewMatches:
      return "too few matches";
    case Reason::kSmallBaseline:
      return "small baseline";
    case Reason::kNoDominantPlane:
      return "no dominant plane";
    case Reason::kNoTargetPlane:
      return "no target plane";
    case Reason::kNoOpening:
      return "no opening";
    case Reason::kDecompositionFailed:
      return "decomposition failed";
    case Reason::kBadImage:
      return "bad image";
    case Reason::kPartialView:
      return "target partly out of view";
    case Reason::kLowParallax:
      return "too little parallax to measure the opening";
    case Reason::kMotionBlur:
      return "motion blur";
    case Reason::kTopNotParallel:
      return "top not parallel to the floor";
    case Reason::kNoFloorAroundTop:
      return "no floor around the top";
    case Reason::kTopFitsFloor:
      return "top fits the floor";
    case Reason::kTopTilted:
      return "top tilted";
    case Reason::kHeightOutOfRange:
      return "height out of range";
    case Reason::kTopPhotometry:
      return "photometric check failed on the top";
    case Reason::kFloorPhotometry:
      return "photometric check failed on the floor";
    case Reason::kTopFitDiverged:
      return "top's fit diverged";
    case Reason::kTopAloneTooFew:
      return "top alone: too few matches on it";
    case Reason::kTopAloneFloorSeen:
      return "top alone: floor in sight";
    case Reason::kTopAloneLowRise:
      return "top alone: too little above the floor";
    case Reason::kTopAloneLowParallax:
      return "top alone: too little parallax";
    case Reason::kMotionDisagrees:
      return "motion disagrees with motion capture";
    case Reason::kOpeningTooSmall:
      return "opening too small";
    case Reason::kNotBehindWall:
      return "view not behind the wall";
    case Reason::kPartialNotFramed:
      return "partial view without the wall around it";
    case Reason::kPartialNotBehind:
      return "partial view not behind the wall";
    case Reason::kExposureChange:
      return "exposure change";
    case Reason::kDuplicateFrame:
      return "duplicated frame";
    case Reason::kFrameGap:
      return "frames missing (gap)";
    case Reason::kTopParallaxGap:
      return "top near the epipole (parallax gap)";
    case Reason::kOutlineOnFloor:
      return "featureless outline on the floor";
    case Reason::kOutlineUnmatched:
      return "featureless outline not in the reference";
    case Reason::kOutlineSilent:
      return "featureless outline too faint to place";
    case Reason::kTopRunsOn:
      return "top runs on past its features or outline";
    case Reason::kTopTooSmall:
      return "featureless outline narrower than the gear";
    case Reason::kDecompositionAmbiguous:
      return "decomposition ambiguous (no prior)";
    case Reason::kPlanesDisagree:
      return "the two planes' motions disagree";
    case Reason::kAlignedPlaneBehind:
      return "aligned plane behind a camera";
    case Reason::kAimBehindCamera:
      return "target's centre not in front of the camera";
    case Reason::kCornerOffPlane:
      return "outline corner off its plane";
    case Reason::kTopPointsFew:
      return "too few top features on its plane";
    case Reason::kTopMatchesFew:
      return "too few matches at the top's height";
    case Reason::kNoTopHeight:
      return "nothing above the known floor";
  }
  return "unknown";
}

}  // namespace alight::vision
