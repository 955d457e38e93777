// The onboard estimator's network input: a first byte picks the message, the rest is
// its LCM encoding: range_t, baro_t or imu_t, decoded and converted as alight-estimator does and
// fed to a filter that has finished its alignment (then a few more IMU samples, so a stored
// value reaches the propagation); or state_estimate_t as alight-autonomy reads it. Whatever the
// bytes, the filter's state stays finite.
#include <cstdlib>

#include "autonomy/convert.hpp"
#include "estimator/convert.hpp"
#include "estimator/estimator.hpp"
#include "fuzz/fuzz_support.hpp"

namespace {

using namespace alight;

const estimator::Estimator& aligned_filter() {
  static const estimator::Estimator filter = [] {
    estimator::Estimator f{estimator::EstimatorParams{}};
    estimator::ImuSample imu;
    imu.accel_B = Vector3d(0, 0, 9.80665);
    for (int k = 1; k <= 400; ++k) {
      imu.utime = 1'000'000 + 5000 * k;
      f.add_imu(imu);
    }
    return f;
  }();
  return filter;
}

void still(estimator::Estimator& f, int n) {
  estimator::ImuSample imu;
  imu.accel_B = Vector3d(0, 0, 9.80665);
  for (int k = 0; k < n; ++k) {
    imu.utime = f.state().utime + 5000;
    f.add_imu(imu);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const uint8_t which = data[0] % 4;
  ++data;
  --size;
  if (which == 3) {
    const auto msg = fuzz::decode<state_estimate_t>(data, size);
    if (!msg) return 0;
    std::string why;
    (void)autonomy::estimate_from_msg(*msg, &why);
    return 0;
  }
  estimator::Estimator filter = aligned_filter();
  if (which == 0) {
    const auto msg = fuzz::decode<range_t>(data, size);
    if (!msg) return 0;
    filter.add_range(estimator::from_msg(*msg));
  } else if (which == 1) {
    const auto msg = fuzz::decode<baro_t>(data, size);
    if (!msg) return 0;
    filter.add_baro(estimator::from_msg(*msg));
  } else {
    const auto msg = fuzz::decode<imu_t>(data, size);
    if (!msg) return 0;
    filter.add_imu(estimator::from_msg(*msg));
  }
  still(filter, 20);
  const estimator::State s = filter.state();
  if (!s.p_W_B.allFinite() || !s.v_W_B.allFinite() || !s.q_WB.coeffs().allFinite() ||
      !s.cov.allFinite())
    std::abort();
  return 0;
}
