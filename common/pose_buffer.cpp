#include "common/pose_buffer.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>

#include "common/param_schema.hpp"

namespace alight {

const ParamSchema<PoseBufferParams>& PoseBufferParams::schema() {
  using P = PoseBufferParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("history_s", &P::history_s, Range::gt(0), "s",
          "samples older than the newest minus this are dropped");
    s.add("max_gap_s", &P::max_gap_s, Range::gt(0), "s",
          "never interpolate across a larger gap between samples");
    s.add("max_extrapolation_s", &P::max_extrapolation_s, Range::ge(0), "s",
          "how far past the newest sample a query may reach (constant velocity)");
    return s;
  }();
  return schema;
}

void PoseBufferParams::validate() const { schema().validate(*this); }

PoseBuffer::PoseBuffer(const PoseBufferParams& params) : params_(params) { params_.validate(); }

bool PoseBuffer::add(const PoseSample& sample) {
  const auto history_us = static_cast<int64_t>(params_.history_s * 1e6);
  // Saturating: a pose stamped near INT64_MIN made `utime - history_us` overflow, which emptied
  // the buffer below and read front() of an empty deque (found by fuzzing).
  const auto window_start = [history_us](int64_t newest) {
    return newest < INT64_MIN + history_us ? INT64_MIN : newest - history_us;
  };
  if (!samples_.empty() && sample.utime < window_start(samples_.back().utime)) return false;
  auto it = std::lower_bound(samples_.begin(), samples_.end(), sample.utime,
                             [](const PoseSample& s, int64_t t) { return s.utime < t; });
  if (it != samples_.end() && it->utime == sample.utime) {
    *it = sample;
  } else {
    samples_.insert(it, sample);
  }
  while (samples_.front().utime < window_start(samples_.back().utime)) samples_.pop_front();
  return true;
}

PoseSample interpolate(const PoseSample& a, const PoseSample& b, double s) {
  PoseSample out;
  out.utime =
      a.utime + static_cast<int64_t>(std::llround(s * static_cast<double>(b.utime - a.utime)));
  out.p_W_B = a.p_W_B + s * (b.p_W_B - a.p_W_B);
  out.v_W_B = a.v_W_B + s * (b.v_W_B - a.v_W_B);
  out.omega_B = a.omega_B + s * (b.omega_B - a.omega_B);
  out.q_WB = a.q_WB.slerp(s, b.q_WB).normalized();
  return out;
}

PoseBuffer::Status PoseBuffer::lookup(int64_t utime, PoseSample* out) const {
  assert(out != nullptr);
  if (samples_.empty()) return Status::kEmpty;
  if (utime < samples_.front().utime) return Status::kBeforeHistory;
  const PoseSample& newest = samples_.back();
  if (utime > newest.utime) {
    const double dt_s = 1e-6 * static_cast<double>(utime - newest.utime);
    if (dt_s > params_.max_extrapolation_s) return Status::kAfterNewest;
    *out = newest;
    out->utime = utime;
    out->p_W_B = newest.p_W_B + dt_s * newest.v_W_B;
    const Vector3d rot = newest.omega_B * dt_s;
    if (rot.norm() > 0)
      out->q_WB =
          (newest.q_WB * Quaterniond(Eigen::AngleAxisd(rot.norm(), rot.normalized()))).normalized();
    return Status::kOk;
  }
  auto hi = std::lower_bound(samples_.begin(), samples_.end(), utime,
                             [](const PoseSample& s, int64_t t) { return s.utime < t; });
  if (hi->utime == utime) {
    *out = *hi;
    return Status::kOk;
  }
  const PoseSample& b = *hi;
  const PoseSample& a = *(hi - 1);
  if (1e-6 * static_cast<double>(b.utime - a.utime) > params_.max_gap_s) return Status::kGap;
  const double s = static_cast<double>(utime - a.utime) / static_cast<double>(b.utime - a.utime);
  *out = interpolate(a, b, s);
  out->utime = utime;
  return Status::kOk;
}

std::optional<PoseSample> PoseBuffer::at(int64_t utime) const {
  PoseSample s;
  if (lookup(utime, &s) != Status::kOk) return std::nullopt;
  return s;
}

}  // namespace alight
