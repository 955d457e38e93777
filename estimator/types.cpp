#include "estimator/types.hpp"

namespace alight::estimator {

const char* to_string(Outcome o) {
  switch (o) {
    case Outcome::kFused:
      return "fused";
    case Outcome::kQueued:
      return "queued";
    case Outcome::kNonFinite:
      return "non_finite";
    case Outcome::kAbsurd:
      return "absurd";
    case Outcome::kOutOfOrder:
      return "out_of_order";
    case Outcome::kTooOld:
      return "too_old";
    case Outcome::kTooNew:
      return "too_new";
    case Outcome::kNotInitialised:
      return "not_initialised";
    case Outcome::kInvalid:
      return "invalid";
    case Outcome::kOutOfRange:
      return "out_of_range";
    case Outcome::kBeamAngle:
      return "beam_angle";
    case Outcome::kGate:
      return "gate";
    case Outcome::kTooFewInliers:
      return "too_few_inliers";
    case Outcome::kGeometry:
      return "geometry";
    case Outcome::kNoClone:
      return "no_clone";
    case Outcome::kQueueFull:
      return "queue_full";
    case Outcome::kDuplicate:
      return "duplicate";
    case Outcome::kNumerical:
      return "numerical";
    case Outcome::kCount:
      break;
  }
  return "?";
}

const char* to_string(Sensor s) {
  switch (s) {
    case Sensor::kImu:
      return "imu";
    case Sensor::kRange:
      return "range";
    case Sensor::kBaro:
      return "baro";
    case Sensor::kFlow:
      return "flow";
    case Sensor::kCount:
      break;
  }
  return "?";
}

const char* to_string(Health h) {
  switch (h) {
    case Health::kOk:
      return "OK";
    case Health::kDegraded:
      return "DEGRADED";
    case Health::kLost:
      return "LOST";
  }
  return "?";
}

int64_t Counters::rejected(Sensor s) const {
  int64_t n = 0;
  for (int o = 0; o < kOutcomeCount; ++o)
    if (o != static_cast<int>(Outcome::kFused) && o != static_cast<int>(Outcome::kQueued))
      n += by_outcome[static_cast<int>(s)][o];
  return n;
}

std::string health_reasons_text(uint32_t reasons) {
  static constexpr std::pair<uint32_t, const char*> kNames[] = {
      {kNotInitialised, "not_initialised"},
      {kNoFlow, "no_flow"},
      {kNoRange, "no_range"},
      {kNoBaro, "no_baro"},
      {kPositionUncertain, "position_uncertain"},
      {kVelocityUncertain, "velocity_uncertain"},
      {kImuGap, "imu_gap"},
      {kImuStopped, "imu_stopped"},
      {kHeightUncertain, "height_uncertain"}};
  std::string out;
  for (const auto& [bit, name] : kNames)
    if (reasons & bit) out += (out.empty() ? "" : "|") + std::string(name);
  return out;
}

}  // namespace alight::estimator
