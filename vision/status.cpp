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
  }
  return "unknown";
}

}  // namespace alight::vision
