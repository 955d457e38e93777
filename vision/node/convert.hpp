#pragma once
// FrameResult (the pipeline's per-frame outcome) to the VISION_TARGET message (target_t), as the
// alight-vision node publishes it; a free function so tests and the in-process closed loop use
// exactly the node's conversion.

#include <alight/platform_motion_t.hpp>
#include <alight/target_t.hpp>
#include <optional>

#include "vision/pipeline.hpp"

namespace alight::vision {

/// Found targets carry every field; a target located only (cut by the image border,
/// REASON_PARTIAL_VIEW, or an opening seen with too little parallax, REASON_LOW_PARALLAX)
/// still says where to look (waypoint, normal, pixel, sizes); other failures carry the reason
/// and the counts only.
target_t to_msg(const FrameResult& r);

/// The moving top's measurement (VISION_PLATFORM) of a frame that has one (FrameResult::moving);
/// not found: the reason and the counts only.
std::optional<platform_motion_t> to_platform_msg(const FrameResult& r);

}  // namespace alight::vision
