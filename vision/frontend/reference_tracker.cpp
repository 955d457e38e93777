// Paper 3.1.1: reference frame by continuous tracking; see reference_tracker.hpp.
#include "vision/frontend/reference_tracker.hpp"

#include <algorithm>
#include <unordered_map>
#include <unordered_set>

#include "vision/geometry/homography.hpp"

namespace alight::vision {

ReferenceTracker::ReferenceTracker(const TrackerParams& params) : params_(params) {
  params_.validate();
}

void ReferenceTracker::reset() { history_.clear(); }

ReferenceTracker::Update ReferenceTracker::add(TrackedFrame frame) {
  Update out;
  const int n = int(frame.keypoints.size());
  assert(frame.descriptors.rows == n);
  if (n < params_.min_tracked) {
    out.reset = !history_.empty();
    history_.clear();
    out.status = Reason::kTooFewFeatures;
    return out;
  }
  if (!history_.empty()) {
    const int64_t dt = frame.utime - history_.back()->utime;
    if (dt <= 0 || double(dt) * 1e-6 > params_.max_frame_gap_s) {
      history_.clear();
      out.reset = true;
    }
  }
  frame.track_id.assign(n, -1);
  if (!history_.empty()) {
    const TrackedFrame& prev = *history_.back();
    const auto s_prev = response_signs(prev.keypoints), s_cur = response_signs(frame.keypoints);
    const auto m =
        match_descriptors(prev.descriptors, frame.descriptors, params_.match, &s_prev, &s_cur);
    std::vector<uint8_t> keep(m.size(), 1);
    if (params_.frame_threshold_px > 0.0) {
      std::vector<Vector2d> a, b;
      for (const auto& mm : m) {
        a.emplace_back(prev.keypoints[mm.i1].x, prev.keypoints[mm.i1].y);
        b.emplace_back(frame.keypoints[mm.i2].x, frame.keypoints[mm.i2].y);
      }
      HomographyParams hp;
      hp.threshold_px = params_.frame_threshold_px;
      hp.seed = params_.seed;
      hp.refine_iterations = 0;
      const auto fit = fit_homography(a, b, hp);
      if (fit)
        keep = fit->inlier;
      else
        keep.assign(m.size(), 0);
    }
    for (size_t k = 0; k < m.size(); ++k) {
      if (!keep[k]) continue;
      frame.track_id[m[k].i2] = prev.track_id[m[k].i1];
      ++out.n_frame_matches;
    }
  }
  for (auto& id : frame.track_id)
    if (id < 0) id = next_id_++;
  auto cur = std::make_shared<TrackedFrame>(std::move(frame));
  out.current = cur;

  // Age limit, then the oldest frame that still shares min_tracked tracks with the new one.
  while (!history_.empty() &&
         double(cur->utime - history_.front()->utime) * 1e-6 > params_.max_reference_age_s)
    history_.pop_front();
  const std::unordered_set<int64_t> ids(cur->track_id.begin(), cur->track_id.end());
  auto common = [&](const TrackedFrame& f) {
    int c = 0;
    for (const int64_t id : f.track_id) c += ids.count(id) ? 1 : 0;
    return c;
  };
  while (!history_.empty() && common(*history_.front()) < params_.min_tracked)
    history_.pop_front();  // counts only fall with time: this frame can never qualify again
  if (history_.empty()) {
    out.reset = out.reset || out.n_frame_matches > 0;
    out.status = Reason::kNoReference;
  } else {
    out.reference = history_.front();
    out.n_tracked = common(*history_.front());
    out.status = Reason::kOk;
  }
  history_.push_back(cur);
  while (int(history_.size()) > params_.max_history) history_.pop_front();
  return out;
}

std::vector<Match> tracked_matches(const TrackedFrame& a, const TrackedFrame& b) {
  std::unordered_map<int64_t, int> index;
  index.reserve(b.track_id.size());
  for (size_t j = 0; j < b.track_id.size(); ++j) index.emplace(b.track_id[j], int(j));
  std::vector<Match> out;
  for (size_t i = 0; i < a.track_id.size(); ++i) {
    const auto it = index.find(a.track_id[i]);
    if (it != index.end()) out.push_back({int(i), it->second, 0.f});
  }
  return out;
}

}  // namespace alight::vision
