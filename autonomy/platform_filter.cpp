// The moving platform's constant-velocity filter and the deck's heave fit (platform_filter.hpp).
#include "autonomy/platform_filter.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <optional>
#include <vector>

namespace alight::autonomy {
namespace {

// The platform's axes repeat every quarter turn: its yaw is kept in (-pi/4, pi/4] and every
// innovation wrapped there (a top seen in part can swap its long and short sides).
double wrap_quarter(double a) {
  a = std::remainder(a, M_PI / 2);
  if (a <= -M_PI / 4) a += M_PI / 2;
  return a;
}

bool finite(const PlatformMeasurement& m) {
  return m.p_W.allFinite() && m.v_W.allFinite() && m.cov_p_W.allFinite() && m.cov_v_W.allFinite() &&
         std::isfinite(m.yaw_rad) && std::isfinite(m.yaw_rate_rps) && std::isfinite(m.var_yaw) &&
         std::isfinite(m.var_yaw_rate) && m.var_yaw >= 0 && m.var_yaw_rate >= 0;
}

// Continuous white-acceleration process noise of a constant-velocity pair over dt.
Matrix2d cv_noise(double psd, double dt) {
  Matrix2d Q;
  Q << dt * dt * dt / 3, dt * dt / 2, dt * dt / 2, dt;
  return psd * Q;
}

}  // namespace

const ParamSchema<PlatformFilterParams>& PlatformFilterParams::schema() {
  using P = PlatformFilterParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("accel_psd", &P::accel_psd, Range::gt(0), "m^2/s^3",
          "white acceleration driving the platform's constant-velocity model (a cart's turns)");
    s.add("yaw_accel_psd", &P::yaw_accel_psd, Range::gt(0), "rad^2/s^3",
          "white angular acceleration driving its yaw rate");
    s.add("gate_chi2", &P::gate_chi2, Range::gt(0), "",
          "a measurement's position and velocity innovation beyond this (4 dof) is refused");
    s.add("max_consecutive_rejections", &P::max_consecutive_rejections, Range::ge(1), "",
          "refused in a row: the refused measurements' own track replaces the filter's (once "
          "believed, if the filter's is)");
    s.add("min_consistent", &P::min_consistent, Range::ge(2), "",
          "measurements in a row within the gate before a track's motion is believed");
    s.add("stale_s", &P::stale_s, Range::gt(0), "s",
          "no measurement for this long: the filter starts over");
    s.add("min_sigma_m", &P::min_sigma_m, Range::gt(0), "m",
          "floor on a measurement's position sigma");
    s.add("min_sigma_mps", &P::min_sigma_mps, Range::gt(0), "m/s",
          "floor on a measurement's velocity sigma");
    s.add("course_tau_s", &P::course_tau_s, Range::gt(0), "s",
          "the course's turn rate (a cart round a bend) smoothed over this; the prediction "
          "turns the velocity at it");
    s.add("heave_window_s", &P::heave_window_s, Range::gt(0), "s",
          "the vertical velocities the heave is fitted to");
    s.add("heave_min_hz", &P::heave_min_hz, Range::gt(0), "Hz", "lowest heave frequency fitted");
    s.add("heave_max_hz", &P::heave_max_hz, Range::gt(0), "Hz", "highest heave frequency fitted")
        .check([](const P& p) { return p.heave_max_hz > p.heave_min_hz; },
               "must exceed heave_min_hz");
    return s;
  }();
  return schema;
}

void PlatformFilterParams::validate() const { schema().validate(*this); }

double HeaveModel::vz(int64_t utime) const {
  if (!(w_rps > 0)) return 0.0;
  const double t = double(utime - t0_utime) * 1e-6;
  return a * std::sin(w_rps * t) + b * std::cos(w_rps * t) + c;
}

double HeaveModel::z(int64_t utime) const {
  if (!(w_rps > 0)) return 0.0;
  const double t = double(utime - t0_utime) * 1e-6;
  return (-a * std::cos(w_rps * t) + b * std::sin(w_rps * t)) / w_rps;
}

namespace {

// The heave's frequencies for a window spanning span_s: a sine is told from a drift only over
// most of a period; none where no frequency of the band is.
std::vector<double> heave_frequencies_hz(double span_s, double min_hz, double max_hz) {
  std::vector<double> f;
  const double lo_hz = std::max(min_hz, 0.6 / std::max(span_s, 1e-3));
  if (!(lo_hz < max_hz)) return f;
  constexpr int kGrid = 60;
  for (int k = 0; k <= kGrid; ++k) f.push_back(lo_hz * std::pow(max_hz / lo_hz, double(k) / kGrid));
  return f;
}

// One sample's row of the vertical model at angular frequency w (0: no sine) and time t from the
// window's start: vz = a sin + b cos + c + (dh + z(t)) g, z(t) = (-a cos + b sin) / w the heave's
// height (TopHeight: the height's error is the plane's distance to the top, heave included).
Eigen::Vector4d vertical_row(const VerticalSample& s, double w, double t) {
  if (!(w > 0)) return Eigen::Vector4d(0, 0, 1, s.g_per_s);
  const double sn = std::sin(w * t), cs = std::cos(w * t);
  return Eigen::Vector4d(sn - s.g_per_s * cs / w, cs + s.g_per_s * sn / w, 1, s.g_per_s);
}

struct VerticalFit {
  Eigen::Vector4d x = Eigen::Vector4d::Zero();  // a, b, c, dh
  double w = 0, sse = INFINITY, var_dh = 0;
  size_t n = 0;  // samples fitted
};

// Least squares of the vertical model over the samples per frequency of the band (none over
// less than most of a period: drift and dh alone), the best one's. dh_given: dh held at it
// (the heave's fit), else fitted; priors (kHeaveDriftSigmaMps, kTopHeightPriorSigmaM) only where
// dh is fitted, each velocity of kVerticalSigmaMps.
VerticalFit fit_vertical(const std::deque<VerticalSample>& samples, double min_hz, double max_hz,
                         std::optional<double> dh_given) {
  VerticalFit best;
  const int64_t t0 = samples.front().utime;
  const double span_s = double(samples.back().utime - t0) * 1e-6;
  std::vector<double> freqs = heave_frequencies_hz(span_s, min_hz, max_hz);
  if (dh_given && freqs.empty()) return best;  // the heave's fit needs a sine
  if (freqs.empty()) freqs.push_back(0.0);
  // Each velocity is a mean over its interval, and the camera's frames come several to an
  // interval: the samples' errors are shared by the ones within an interval of each other, so
  // the window holds only as many independent ones as intervals fit in its span; each sample
  // weighs that share of an independent one.
  double interval_s = 0;
  for (const auto& s : samples) interval_s += s.interval_s;
  interval_s /= double(samples.size());
  const double n_samples = double(samples.size());
  const double shared =
      n_samples / std::clamp(span_s / std::max(interval_s, 1e-3) + 1, 1.0, n_samples);
  const double wv = 1.0 / (kVerticalSigmaMps * kVerticalSigmaMps * shared);
  const int n = dh_given ? 3 : 4;
  for (const double f : freqs) {
    const double w = 2 * M_PI * f;
    Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
    Eigen::Vector4d y = Eigen::Vector4d::Zero();
    for (const auto& s : samples) {
      const Eigen::Vector4d r = vertical_row(s, w, double(s.utime - t0) * 1e-6);
      const double v = s.vz_mps - (dh_given ? *dh_given * s.g_per_s : 0.0);
      A += wv * r * r.transpose();
      y += wv * r * v;
    }
    if (!(w > 0)) A(0, 0) += 1.0, A(1, 1) += 1.0;  // no sine: its terms pinned at zero
    if (!dh_given) {
      A(2, 2) += 1.0 / (kHeaveDriftSigmaMps * kHeaveDriftSigmaMps);
      A(3, 3) += 1.0 / (kTopHeightPriorSigmaM * kTopHeightPriorSigmaM);
    }
    const Eigen::MatrixXd An = A.topLeftCorner(n, n);
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(An);
    if (ldlt.info() != Eigen::Success) continue;
    Eigen::Vector4d x = Eigen::Vector4d::Zero();
    x.head(n) = ldlt.solve(y.head(n));
    if (dh_given) x(3) = *dh_given;
    if (!x.allFinite()) continue;
    double sse = 0;
    for (const auto& s : samples) {
      const double r = s.vz_mps - vertical_row(s, w, double(s.utime - t0) * 1e-6).dot(x);
      sse += r * r;
    }
    if (!(sse < best.sse)) continue;
    best.x = x, best.w = w, best.sse = sse, best.n = samples.size();
    if (!dh_given) best.var_dh = ldlt.solve(Eigen::VectorXd::Unit(4, 3))(3);
  }
  return best;
}

}  // namespace

HeaveModel fit_heave(const std::deque<VerticalSample>& samples, double dh_m, double min_hz,
                     double max_hz) {
  HeaveModel h;
  if (samples.size() < 8) return h;
  const VerticalFit f = fit_vertical(samples, min_hz, max_hz, dh_m);
  if (!(f.w > 0)) return h;
  h.w_rps = f.w, h.a = f.x(0), h.b = f.x(1), h.c = f.x(2), h.t0_utime = samples.front().utime;
  h.rms_mps = std::sqrt(f.sse / double(samples.size()));
  return h;
}

// dh and the heave fitted together (vertical_row), dh's variance the normal matrix's inverse
// scaled up by the residuals where they exceed kVerticalSigmaMps.
TopHeight fit_top_height(const std::deque<VerticalSample>& samples, double min_hz, double max_hz) {
  TopHeight h;
  if (samples.size() < 8) return h;
  VerticalFit f = fit_vertical(samples, min_hz, max_hz, std::nullopt);
  if (!(f.var_dh > 0)) return h;
  // Fitted again without the velocities beyond kVerticalOutlierSigmas of the residuals' robust
  // spread (a mismatched set, a burst of a sea state's misfit): a few frames of them would pull
  // dh by centimetres where the camera moves fast vertically (g large).
  const int64_t t0 = samples.front().utime;
  std::vector<double> abs_r;
  for (const auto& s : samples)
    abs_r.push_back(
        std::abs(s.vz_mps - vertical_row(s, f.w, double(s.utime - t0) * 1e-6).dot(f.x)));
  std::vector<double> sorted = abs_r;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double spread = std::max(0.5 * kVerticalSigmaMps, 1.4826 * sorted[sorted.size() / 2]);
  std::deque<VerticalSample> kept;
  for (size_t i = 0; i < samples.size(); ++i)
    if (abs_r[i] <= kVerticalOutlierSigmas * spread) kept.push_back(samples[i]);
  if (kept.size() < samples.size() && kept.size() >= 8) {
    const VerticalFit g = fit_vertical(kept, min_hz, max_hz, std::nullopt);
    if (g.var_dh > 0) f = g;
  }
  const double misfit =
      f.sse / std::max(1.0, double(f.n) - 4) / (kVerticalSigmaMps * kVerticalSigmaMps);
  h.dh_m = f.x(3);
  h.var_m2 = f.var_dh * std::max(1.0, misfit);
  h.utime = samples.back().utime;
  return h;
}

namespace {

// g of TopHeight: the vertical velocity a height error of one metre adds to the measurement, the
// top taken dh_m above vision's plane [1/s]; 0 without cameras or with the earlier camera within
// kMinPlacingRangeM of the top.
double height_error_rate(const PlatformMeasurement& m, double dh_m) {
  if (!m.placed_from_cameras()) return 0.0;
  const double range_1 = m.ref_camera_W.z() - m.plane_z_m - dh_m;
  if (!(range_1 >= kMinPlacingRangeM)) return 0.0;
  const double dt = double(m.utime - m.ref_utime) * 1e-6;
  return (m.ref_camera_W.z() - m.camera_W.z()) / (dt * range_1);
}

}  // namespace

PlatformMeasurement placed_at_height(const PlatformMeasurement& m, double dh_m) {
  if (!m.placed_from_cameras() || dh_m == 0.0) return m;
  const double range_2 = m.camera_W.z() - m.plane_z_m, range_1 = m.ref_camera_W.z() - m.plane_z_m;
  if (!(std::min(range_1, range_2) - dh_m >= kMinPlacingRangeM)) return m;
  const double dt = double(m.utime - m.ref_utime) * 1e-6;
  // Each view's points lie k times as far from its camera's nadir as the top's.
  const double k = range_2 / (range_2 - dh_m);
  const double g = height_error_rate(m, dh_m);
  PlatformMeasurement out = m;
  const Vector2d nadir = m.camera_W.head<2>();
  out.p_W.head<2>() = nadir + (m.p_W.head<2>() - nadir) / k;
  out.p_W.z() += dh_m - dh_m * g * dt;
  const Vector2d v_cam = (m.camera_W - m.ref_camera_W).head<2>() / dt;
  out.v_W.head<2>() = v_cam + (m.v_W.head<2>() - v_cam) / k;
  out.v_W.z() -= dh_m * g;
  out.size_m /= k;
  out.cov_p_W.topLeftCorner<2, 2>() /= k * k;
  out.cov_v_W.topLeftCorner<2, 2>() /= k * k;
  return out;
}

PlatformFilter::PlatformFilter(const PlatformFilterParams& params) : params_(params) {
  params_.validate();
}

const char* PlatformFilter::to_string(Refusal r) {
  switch (r) {
    case Refusal::kNotFinite:
      return "not finite";
    case Refusal::kOutOfOrder:
      return "out of order";
    case Refusal::kGate:
      return "beyond the gate";
    case Refusal::kLargerThanTheTop:
      return "larger than the top";
    case Refusal::kBeyondReach:
      return "a velocity beyond the platform's reach";
  }
  return "?";
}

void PlatformFilter::reset() {
  track_ = Track{};
  candidate_ = Track{};
  consecutive_rejections_ = 0;
}

void PlatformFilter::refuse(Refusal r) {
  ++n_rejected_;
  ++refused_[static_cast<int>(r)];
}

bool PlatformFilter::believed(const Track& t) const {
  return t.t_utime != 0 && t.n_consistent >= params_.min_consistent &&
         double(t.t_utime - t.since_utime) * 1e-6 >= kConfirmS;
}

double worst_axis_var(const Matrix2d& cov) {
  return Eigen::SelfAdjointEigenSolver<Matrix2d>(cov, Eigen::EigenvaluesOnly)
      .eigenvalues()
      .maxCoeff();
}

PlatformFilter::Prediction PlatformFilter::predict(const Track& t, int64_t utime) const {
  Prediction p;
  const double dt = std::max(0.0, double(utime - t.t_utime) * 1e-6);
  // The path's turn (a cart round a bend): the velocity turned at the course's rate over dt.
  const double w = t.course_rate, a = w * dt;
  const Vector2d v = t.x.tail<2>(), v_perp(-v.y(), v.x());
  if (std::abs(a) > 1e-6) {
    p.p_W = t.x.head<2>() + (std::sin(a) * v + (1 - std::cos(a)) * v_perp) / w;
    p.v_W = std::cos(a) * v + std::sin(a) * v_perp;
  } else {
    p.p_W = t.x.head<2>() + dt * v;
    p.v_W = v;
  }
  p.a_W = w * Vector2d(-p.v_W.y(), p.v_W.x());
  Eigen::Matrix4d F = Eigen::Matrix4d::Identity();
  F.topRightCorner<2, 2>() = dt * Matrix2d::Identity();
  Eigen::Matrix4d Pp = F * t.P * F.transpose();
  const Matrix2d q = cv_noise(params_.accel_psd, dt);
  for (int i = 0; i < 2; ++i) {
    Pp(i, i) += q(0, 0), Pp(i, i + 2) += q(0, 1), Pp(i + 2, i) += q(1, 0),
        Pp(i + 2, i + 2) += q(1, 1);
  }
  p.cov_p = Pp.topLeftCorner<2, 2>();
  p.cov_v = Pp.bottomRightCorner<2, 2>();
  p.travelled_m = (p.p_W - t.p_start).norm();
  p.yaw_rad = wrap_quarter(t.yaw(0) + dt * t.yaw(1));
  p.long_axis_known = std::abs(t.long_votes) >= kLongAxisVotes;
  p.long_yaw_rad = wrap_axis_angle(t.yaw(0) + dt * t.yaw(1) + (t.long_votes < 0 ? M_PI / 2 : 0.0));
  p.yaw_rate_rps = t.yaw(1);
  p.var_yaw = t.P_yaw(0, 0) + 2 * dt * t.P_yaw(0, 1) + dt * dt * t.P_yaw(1, 1) +
              cv_noise(params_.yaw_accel_psd, dt)(0, 0);
  // Vision's z is its plane's plus the heave it read, which holds dh g dt of the height's error.
  p.top_z_m = t.n_z > 0 ? (t.top_z_sum + t.dh_m * (double(t.n_z) - t.g_dt_sum)) / t.n_z : 0.0;
  return p;
}

namespace {

// The measurement's covariances, floored: vision's residuals can be optimistic.
Eigen::Matrix4d measurement_cov(const PlatformMeasurement& m, const PlatformFilterParams& params) {
  Eigen::Matrix4d R = Eigen::Matrix4d::Zero();
  R.topLeftCorner<2, 2>() = m.cov_p_W.topLeftCorner<2, 2>() +
                            params.min_sigma_m * params.min_sigma_m * Matrix2d::Identity();
  R.bottomRightCorner<2, 2>() = m.cov_v_W.topLeftCorner<2, 2>() +
                                params.min_sigma_mps * params.min_sigma_mps * Matrix2d::Identity();
  return R;
}

}  // namespace

namespace {

// A part of the top's position variance: no information [m^2].
constexpr double kUnknownPositionVar = 1e2;
// The yaw of a view whose extent is not the whole top's is its features' rectangle's, a
// cluster's, whatever the spread of its features says: known only to the quarter turn (uniform
// over it) [rad^2]. Its turn between the frames stays the top's.
constexpr double kUnknownYawVar = (M_PI / 4) * (M_PI / 4) / 3;
// A view marked cut that spans the whole top: its centre's sigma [m], its extent's tolerance
// (kPartialViewM) halved.
constexpr double kCutWholeSigmaM = 0.5 * kPartialViewM;
// The whole top's extent is judged among this many of the latest views: ten seconds of them and
// more, a long follow's views of part of the top among them.
constexpr size_t kExtentsKept = 256;
// Views that agree on an extent before it can be the whole top's: a fifth of a second of the
// camera's frames.
constexpr int kWholeTopViews = 6;
// The share of the best supported extent's views a larger one must gather to replace the whole
// (whole_extent): a second's views against four seconds of the smaller one's.
constexpr double kLargerShare = 0.25;

Vector2d extent(const PlatformMeasurement& m) {
  return Vector2d(m.size_m.maxCoeff(), m.size_m.minCoeff());
}

// Extent a falls short of extent b on a side by more than a view's scatter (kPartialViewM).
bool shorter_on_a_side(const Vector2d& a, const Vector2d& b) {
  return ((a - b).array() < -kPartialViewM).any();
}

}  // namespace

// The whole top's extent (zero: no view yet) [m]: the extent most of the track's latest views
// agree on (each within kPartialViewM of it on both sides), or, where kWholeTopViews of them agree
// on one that is larger (by more than kPartialViewM on a side, on no side smaller), that one's
// instead, and so on up. A cluster of the floor read as the top is seen in a frame or two; views
// of part of the top differ from one another as the part seen grows (the top entering the view)
// or repeat (the vehicle following at a steady offset), but are smaller than the whole top, seen
// view after view. So neither the first views (a part, or a cluster) nor the most frequent
// decide what the whole top is; and the whole top's extent is its views' best supported one, not
// the largest within their scatter, against which the typical view would fall short.
Vector2d PlatformFilter::whole_extent(const Track& t) {
  const size_t n = t.extents.size();
  // Each view's extent at the top's height as now measured, the deck's heave at the view's
  // exposure included: it shrinks about its camera's nadir by (range - dh - heave) / range. A deck
  // heaving 5 cm under a camera 0.8 m above it scatters its views' extents by +-7 %, and the
  // larger extents' steps up (below) would take the crest's: the whole top believed too large, its
  // own views then short of it by more than kPartialViewM, read as parts (their centres unfused).
  std::vector<Vector2d> e(n);
  for (size_t i = 0; i < n; ++i) {
    const Track::View& v = t.extents[i];
    const double above_m = t.dh_m + t.heave.z(v.utime);
    const bool placed = std::isfinite(v.range_m) && v.range_m - above_m >= kMinPlacingRangeM;
    e[i] = placed ? Vector2d(v.extent * (v.range_m - above_m) / v.range_m) : v.extent;
  }
  std::vector<int> support(n, 0), uncut(n, 0);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < n; ++j) {
      const bool agree = ((e[j] - e[i]).cwiseAbs().array() <= kPartialViewM).all();
      support[i] += agree;
      uncut[i] += agree && !t.extents[j].cut;
    }
  // The best supported of the extents `eligible` admits (of those as well supported, the larger).
  const auto best = [&](const auto& eligible) -> std::optional<size_t> {
    std::optional<size_t> b;
    for (size_t i = 0; i < n; ++i) {
      if (!eligible(i)) continue;
      if (!b || support[i] > support[*b] ||
          (support[i] == support[*b] && e[i].prod() > e[*b].prod()))
        b = i;
    }
    return b;
  };
  auto whole = best([](size_t) { return true; });
  if (!whole) return Vector2d::Zero();
  const double share = kLargerShare * support[*whole];
  for (size_t steps = 0; steps < n; ++steps) {
    const Vector2d w = e[*whole];
    // A larger extent only views cut by the border support must outnumber the views that showed
    // the smaller one uncut: a cut view holding more than the top (the cart's side seen past its
    // edge, placed on the top's plane) does not outgrow a top seen whole inside the image, while
    // a top followed close, seen mostly cut, outgrows the parts of it seen uncut.
    // And one larger than the whole top believed so far must gather a kLargerShare of the
    // best supported extent's support: a view of more than the top (the top with a stretch of floor
    // that moved alike, a cart's side) comes in bursts of a few frames, while the whole top, once
    // in view after its parts, is seen view after view. A whole top believed too large is the
    // dangerous error: the top's own views then read as parts of it (their centres not fused)
    // and the burst's centre places the drop. The whole top believed keeps its place without
    // (a long follow's views of one part outnumber it in the window).
    const int needed = std::max(kWholeTopViews, uncut[*whole] + 1);
    const auto larger = best([&](size_t i) {
      const bool grows = t.whole.minCoeff() > 0 && shorter_on_a_side(t.whole, e[i]);
      return (support[i] >= needed || (uncut[i] > 0 && support[i] >= kWholeTopViews)) &&
             (!grows || support[i] >= share) && !shorter_on_a_side(e[i], w) &&
             shorter_on_a_side(w, e[i]);
    });
    if (!larger) break;
    whole = larger;
  }
  return e[*whole];
}

bool PlatformFilter::spans_whole_top(const Track& t, const PlatformMeasurement& m) {
  if (!(t.whole.minCoeff() > 0) || !(m.size_m.minCoeff() > 0)) return true;
  return ((extent(m) - t.whole).cwiseAbs().array() <= kPartialViewM).all();
}

bool PlatformFilter::shows_whole_top(const Track& t, const PlatformMeasurement& m) {
  if (!cut(m) || !(t.whole.minCoeff() > 0) || !(m.size_m.minCoeff() > 0)) return false;
  return spans_whole_top(t, m);
}

bool PlatformFilter::partial_view(const Track& t, const PlatformMeasurement& m) {
  const Vector2d& whole = t.whole;
  if (!(whole.minCoeff() > 0) || !(m.size_m.minCoeff() > 0)) return false;
  // A view wider than the whole top on one side is no part of it: the whole top believed is not
  // this one's (a cluster seen first), and the view joins the extents that judge it again.
  return shorter_on_a_side(extent(m), whole) && !shorter_on_a_side(whole, extent(m));
}

void PlatformFilter::add_extent(Track& t, const PlatformMeasurement& raw) {
  const double range_m =
      raw.placed_from_cameras() ? raw.camera_W.z() - raw.plane_z_m : double(INFINITY);
  t.extents.push_back({extent(raw), cut(raw), range_m, raw.utime});
  if (t.extents.size() > kExtentsKept) t.extents.pop_front();
  const Vector2d before = t.whole;
  t.whole = whole_extent(t);
  forget_centre_of_another_top(t, before);
  doubt_centre_of_a_part(t, before);
}

// The track's centre was fused from the views that matched the whole top believed before; where
// the whole top is now shorter on a side than that (by more than kPartialViewM), those views were
// of something else (a cluster beside the top, read first) or of more than the top, and their
// centre may lie anywhere the two extents reach: the position's variance grows by that reach
// squared (half the two diagonals), so the next view of the whole top places it rather than being
// refused by the gate against it.
void PlatformFilter::forget_centre_of_another_top(Track& t, const Vector2d& before) {
  if (!(before.minCoeff() > 0) || !shorter_on_a_side(t.whole, before)) return;
  const double reach_m = 0.5 * (before.norm() + t.whole.norm());
  t.P.topLeftCorner<2, 2>() += reach_m * reach_m * Matrix2d::Identity();
  ++t.n_other_tops;
  t.n_placed = 0;
}

// Where the whole top grew instead (longer on a side by more than kPartialViewM, on none
// shorter) past the latest view that placed the centre, that view was of a part of the top: the
// track's first view may be the only one (start() takes its centre whatever it shows), or views
// of part of it were fused while the whole top believed was the part's. A part's centre lies
// within half the difference of the two extents on each side of the top's: the position's
// variance grows by that reach squared, so the whole top's views place it. Views of the larger
// top that placed the centre before it became the whole one (seen uncut, not parts of the
// smaller) leave it as it is. Without, a track begun on a part 15 cm off a 0.44 m top's centre
// refused the whole top's views at the gate, five in a row, and gave way to a candidate begun on
// a view cut by the border, which has no centre and no whole top (test:
// PlatformFilterRegression.ViewsMarkedCutThatSpanTheWholeTopLocateIt).
void PlatformFilter::doubt_centre_of_a_part(Track& t, const Vector2d& before) {
  const Vector2d& placed = t.placed_extent;
  if (!(before.minCoeff() > 0) || shorter_on_a_side(t.whole, before) ||
      !shorter_on_a_side(before, t.whole) || !(placed.minCoeff() > 0) ||
      !shorter_on_a_side(placed, t.whole))
    return;
  const double reach_m = 0.5 * (t.whole - placed).cwiseMax(0.0).norm();
  t.P.topLeftCorner<2, 2>() += reach_m * reach_m * Matrix2d::Identity();
  t.n_placed = 0;
  t.placed_extent = Vector2d::Zero();
}

bool PlatformFilter::larger_than_the_top(const Track& t, const PlatformMeasurement& m) const {
  // A track's first views are often of part of the top (it enters the view across the image's
  // border, or blurred): measured against those, every view of the whole top would be refused
  // until the track went stale. The whole top is known once as many views of it as make the
  // track's motion believed were fused; before that a larger view is judged by the gate alone.
  if (t.extents.size() < static_cast<size_t>(params_.min_consistent)) return false;
  const Vector2d& whole = t.whole;
  assert(whole.minCoeff() > 0);  // only views with a measured size join extents
  return (extent(m).array() > kLargerThanTheTop * whole.array()).any();
}

void PlatformFilter::start(Track& t, const PlatformMeasurement& m) const {
  const double dh_m = t.dh_m;
  t = Track{};
  t.dh_m = dh_m;
  t.x << m.p_W.x(), m.p_W.y(), m.v_W.x(), m.v_W.y();
  t.p_start = m.p_W.head<2>();
  t.P = measurement_cov(m, params_);
  t.yaw = Vector2d(wrap_quarter(m.yaw_rad), m.yaw_rate_rps);
  t.P_yaw = Vector2d(m.var_yaw + 1e-4, m.var_yaw_rate + 1e-4).asDiagonal();
  t.since_utime = m.utime;
}

// The course's turn rate from the filtered velocity's direction (v0 before the update, the track's
// after it, dt apart). A fast top (a cart round a bend): each update's whole turn, not the
// innovation's share of it (the prediction's own turn leaves about half of it), smoothed over
// about course_tau_s. A creeping one: its direction's change over the last kCourseBaselineM of its
// path, where one update's turn is lost in the direction's noise (the filtered velocity's 1-2 cm/s
// on 10 cm/s), yet a circle's turn carries it centimetres aside over a last drop. Below
// kCourseMinSpeedMps the direction is that noise: no turn.
void PlatformFilter::follow_course(Track& t, int64_t utime, const Vector2d& v0, double dt) const {
  const Vector2d v1 = t.x.tail<2>();
  const double speed = v1.norm();
  if (!(dt > 0)) return;
  if (speed < kCourseMinSpeedMps) {
    t.course.clear();
    t.course_rate = 0;
    return;
  }
  const double heading = std::atan2(v1.y(), v1.x());
  if (t.course.empty()) {
    t.course.push_back({utime, heading, 0.0});
  } else {
    const CourseSample& last = t.course.back();
    t.course.push_back(
        {utime, last.heading + wrap_angle(heading - last.heading), last.path_m + speed * dt});
  }
  const double path = t.course.back().path_m;
  while (t.course.size() > 2 && path - t.course[1].path_m >= kCourseBaselineM) t.course.pop_front();
  if (v0.norm() > kFastCourseMps && speed > kFastCourseMps) {
    const double rate = std::atan2(v0.x() * v1.y() - v0.y() * v1.x(), v0.dot(v1)) / dt;
    const double k = std::min(1.0, dt / params_.course_tau_s);
    t.course_rate += k * (rate - t.course_rate);
  } else if (path - t.course.front().path_m >= kCourseBaselineM) {
    const CourseSample& first = t.course.front();
    t.course_rate =
        (t.course.back().heading - first.heading) / (double(utime - first.utime) * 1e-6);
  }
}

namespace {

// The measurement's vertical velocity at its interval's middle, with the velocity a height error
// of one metre adds there (TopHeight) at the height dh_m believed.
VerticalSample vertical_sample(const PlatformMeasurement& raw, double dh_m) {
  return {(raw.utime + raw.ref_utime) / 2, raw.v_W.z(), height_error_rate(raw, dh_m),
          double(raw.utime - raw.ref_utime) * 1e-6};
}

}  // namespace

PlatformFilter::Fused PlatformFilter::fuse(Track& t, const PlatformMeasurement& raw) const {
  if (t.t_utime == 0) t.dh_m = height_.dh_m;
  const PlatformMeasurement m = placed_at_height(raw, t.dh_m);
  const bool partial = partial_view(t, m);
  const bool places = places_centre(t, m);
  bool placed_unchecked = true;  // no centre to test the view against
  if (t.t_utime == 0) {
    start(t, m);
  } else {
    // Unmeasured that long, the prediction's covariance has grown enough to let a wrong
    // measurement through the gate: the track's motion is confirmed again from this one.
    if (double(m.utime - t.t_utime) * 1e-6 > kConfirmS) {
      t.n_consistent = 0;
      t.since_utime = m.utime;
    }
    Eigen::Matrix4d R = measurement_cov(m, params_);
    if (partial) {
      R.topLeftCorner<2, 2>() = kUnknownPositionVar * Matrix2d::Identity();
    } else if (shows_whole_top(t, m)) {
      // Vision marks a view cut when the top's features come near the border, but this one
      // spans the whole top: none of it lies beyond the border, its centre is the top's.
      R.topLeftCorner<2, 2>() =
          (kCutWholeSigmaM * kCutWholeSigmaM + params_.min_sigma_m * params_.min_sigma_m) *
          Matrix2d::Identity();
    }
    // The measured velocity is the mean over vision's interval, the velocity at its middle: in a
    // turn it is turned on to the measurement's time at the course's rate, or each one pulls the
    // track's velocity back into the turn's past and its position out of the turn.
    const double half_interval_s = 0.5 * double(m.utime - m.ref_utime) * 1e-6;
    const double turn = t.course_rate * half_interval_s;
    const Vector2d v_now = Eigen::Rotation2Dd(turn) * Vector2d(m.v_W.head<2>());
    const Eigen::Vector4d z(m.p_W.x(), m.p_W.y(), v_now.x(), v_now.y());
    const double dt = double(m.utime - t.t_utime) * 1e-6;
    const Prediction ahead = predict(t, m.utime);
    Eigen::Vector4d xp;
    xp << ahead.p_W, ahead.v_W;
    Eigen::Matrix4d Pp = Eigen::Matrix4d::Zero();
    {
      Eigen::Matrix4d F = Eigen::Matrix4d::Identity();
      F.topRightCorner<2, 2>() = dt * Matrix2d::Identity();
      Pp = F * t.P * F.transpose();
      const Matrix2d q = cv_noise(params_.accel_psd, dt);
      for (int i = 0; i < 2; ++i) {
        Pp(i, i) += q(0, 0), Pp(i, i + 2) += q(0, 1), Pp(i + 2, i) += q(1, 0),
            Pp(i + 2, i + 2) += q(1, 1);
      }
    }
    // The measured velocity is the measured point's (vision's p_W, the visible part's centre on
    // a view of part of the top): the top's turn adds its lever arm from the centre,
    // v_m = v + w J (p_m - p) with J the quarter turn, so a view of one end of a turning top does
    // not carry the centre along with that end. p_m is where the velocity was taken, exact
    // whatever its variance as the top's centre; w's own variance widens the velocity's.
    const double w = t.yaw(1);
    Matrix2d J;
    J << 0, -1, 1, 0;
    const Vector2d lever = m.p_W.head<2>() - ahead.p_W;
    Eigen::Matrix4d H = Eigen::Matrix4d::Identity();
    H.bottomLeftCorner<2, 2>() = -w * J;
    R.bottomRightCorner<2, 2>() += t.P_yaw(1, 1) * lever.squaredNorm() * Matrix2d::Identity();
    Eigen::Vector4d h = xp;
    h.tail<2>() += w * J * lever;
    placed_unchecked = worst_axis_var(Pp.topLeftCorner<2, 2>()) > kPartialViewM * kPartialViewM;
    const Eigen::Vector4d innov = z - h;
    const Eigen::Matrix4d S = H * Pp * H.transpose() + R;
    const Eigen::LDLT<Eigen::Matrix4d> ldlt(S);
    const double d2 = innov.dot(ldlt.solve(innov));
    if (!(d2 <= params_.gate_chi2)) return Fused::kOutsideGate;
    const Matrix2d var_v = t.P.bottomRightCorner<2, 2>() + R.bottomRightCorner<2, 2>();
    const double reach_mps = kMaxPlatformAccelMps2 * dt + 3.0 * std::sqrt(worst_axis_var(var_v));
    if (innov.tail<2>().norm() > reach_mps) return Fused::kBeyondReach;
    const Eigen::Matrix4d K = Pp * H.transpose() * ldlt.solve(Eigen::Matrix4d::Identity());
    const Vector2d v0 = t.x.tail<2>();
    t.x = xp + K * innov;
    follow_course(t, m.utime, v0, dt);
    t.P = (Eigen::Matrix4d::Identity() - K * H) * Pp;
    t.P = 0.5 * (t.P + t.P.transpose()).eval();
    // Yaw and its rate: the same filter in one dimension pair.
    Matrix2d Fy;
    Fy << 1, dt, 0, 1;
    const Vector2d yp(t.yaw(0) + dt * t.yaw(1), t.yaw(1));
    const Matrix2d Py = Fy * t.P_yaw * Fy.transpose() + cv_noise(params_.yaw_accel_psd, dt);
    const Vector2d iy(wrap_quarter(m.yaw_rad - yp(0)), m.yaw_rate_rps - yp(1));
    Matrix2d Sy = Py;
    Sy(0, 0) += (spans_whole_top(t, m) ? m.var_yaw : std::max(m.var_yaw, kUnknownYawVar)) + 1e-6;
    Sy(1, 1) += m.var_yaw_rate + 1e-6;
    const Matrix2d Ky = Py * Sy.inverse();
    t.yaw = yp + Ky * iy;
    const double unwrapped = t.yaw(0);
    t.yaw(0) = wrap_quarter(t.yaw(0));
    // Wrapped a quarter turn: the axis the votes were for is now the other one.
    if (std::abs(t.yaw(0) - unwrapped) > M_PI / 4) t.long_votes = -t.long_votes;
    t.P_yaw = (Matrix2d::Identity() - Ky) * Py;
  }
  if (places && m.size_m.maxCoeff() - m.size_m.minCoeff() > kPartialViewM) {
    const double along = std::cos(2 * (m.yaw_rad - t.yaw(0)));  // +1 along yaw(0), -1 across
    t.long_votes = std::clamp(t.long_votes + (along >= 0 ? 1.0 : -1.0), -kLongAxisVotesKept,
                              kLongAxisVotesKept);
  }
  t.t_utime = m.utime;
  ++t.n_consistent;
  if (places) t.n_placed = placed_unchecked ? 1 : t.n_placed + 1;
  if (places && m.size_m.minCoeff() > 0) t.placed_extent = extent(m);
  // Every view not cut by the border, whether it shows the whole top or part of it: which it is is
  // judged against the others (whole_extent), never against the first ones alone. A view vision
  // marks cut only once it spans at least the whole top believed so far: a top followed close
  // fills the view, most views of it come near the border, and the whole top is seen in view
  // after view of them; but a part cut off by the border at a steady offset is seen as steadily,
  // and never becomes the whole top.
  const bool spans_whole = t.whole.minCoeff() > 0 && !partial;
  if (m.size_m.minCoeff() > 0 && (!cut(m) || spans_whole)) add_extent(t, raw);
  // The heave: each vertical velocity is the mean over its interval, so at the interval's middle.
  // An outline's is too coarse to read it (PlatformMeasurement::outline): its top is taken on
  // the plane it was placed on, dh below the top believed, without a heave.
  if (raw.outline) {
    t.top_z_sum += raw.placed_from_cameras() ? raw.plane_z_m : raw.p_W.z();
    ++t.n_z;
    return partial ? Fused::kAcceptedPartial : Fused::kAccepted;
  }
  const VerticalSample vz = vertical_sample(raw, t.dh_m);
  t.top_z_sum += raw.p_W.z();
  t.g_dt_sum += vz.g_per_s * double(raw.utime - raw.ref_utime) * 1e-6;
  ++t.n_z;
  t.vz.push_back(vz);
  while (!t.vz.empty() &&
         double(t.vz.back().utime - t.vz.front().utime) * 1e-6 > params_.heave_window_s)
    t.vz.pop_front();
  t.heave = fit_heave(t.vz, t.dh_m, params_.heave_min_hz, params_.heave_max_hz);
  return partial ? Fused::kAcceptedPartial : Fused::kAccepted;
}

// The track's window fitted for the top's height (fit_top_height), kept where it knows the height
// better than the one kept, grown by kTopHeightDriftM2PerS since; the track's whole top and heave
// then judged again at it.
void PlatformFilter::measure_height(Track& t) {
  const TopHeight w = fit_top_height(t.vz, params_.heave_min_hz, params_.heave_max_hz);
  if (!(w.var_m2 > 0)) return;
  const double kept_var =
      height_.var_m2 > 0
          ? height_.var_m2 +
                kTopHeightDriftM2PerS * std::max(0.0, double(w.utime - height_.utime) * 1e-6)
          : double(INFINITY);
  // A window that disagrees (its own variance and the kept one's): adopted only once the windows
  // have disagreed for kTopHeightDisagreeS; one that agrees ends the disagreement.
  const double gap = w.dh_m - height_.dh_m;
  const bool disagrees =
      height_.var_m2 > 0 &&
      gap * gap > kTopHeightGateSigmas * kTopHeightGateSigmas * (w.var_m2 + kept_var);
  if (!disagrees)
    height_.disagreed_utime = 0;
  else if (height_.disagreed_utime == 0)
    height_.disagreed_utime = w.utime;
  if (!(w.var_m2 < kept_var)) return;
  if (disagrees && double(w.utime - height_.disagreed_utime) * 1e-6 < kTopHeightDisagreeS) return;
  height_ = w;
  at_height(t);
  t.heave = fit_heave(t.vz, t.dh_m, params_.heave_min_hz, params_.heave_max_hz);
}

// The track's whole top judged again at the height kept (its views' extents scale with it); not a
// change of top, so the centre is kept.
void PlatformFilter::at_height(Track& t) const {
  if (t.dh_m == height_.dh_m) return;
  t.dh_m = height_.dh_m;
  if (!t.extents.empty()) t.whole = whole_extent(t);
}

bool PlatformFilter::update(const PlatformMeasurement& raw) {
  at_height(track_);
  at_height(candidate_);
  const bool cameras_finite =
      !raw.placed_from_cameras() || (raw.camera_W.allFinite() && raw.ref_camera_W.allFinite());
  if (!finite(raw) || !cameras_finite || raw.utime <= 0 || raw.ref_utime >= raw.utime) {
    refuse(Refusal::kNotFinite);
    return false;
  }
  // Judged as the track's views are: at the top's height.
  const PlatformMeasurement m = placed_at_height(raw, height_.dh_m);
  if (initialised() && m.utime <= track_.t_utime) {
    refuse(Refusal::kOutOfOrder);
    return false;
  }
  const auto stale = [&](const Track& t) {
    return t.t_utime != 0 && double(m.utime - t.t_utime) * 1e-6 > params_.stale_s;
  };
  if (stale(track_)) reset();
  if (stale(candidate_)) candidate_ = Track{};
  if (larger_than_the_top(track_, m)) {
    // Wider on one side but shorter on another, the view is not fused, yet it may be the top
    // and the whole top believed a thin cluster read first: its extent joins the others, and
    // views of the top that outnumber the cluster's make it the whole top again.
    if (shorter_on_a_side(extent(m), track_.whole)) add_extent(track_, raw);
    refuse(Refusal::kLargerThanTheTop);
    return false;
  }
  const auto refused_by = [](Fused f) {
    return f == Fused::kBeyondReach ? Refusal::kBeyondReach : Refusal::kGate;
  };
  const auto fused = [](Fused f) { return f == Fused::kAccepted || f == Fused::kAcceptedPartial; };
  const Fused f = fuse(track_, raw);
  if (fused(f)) {
    if (believed(track_)) measure_height(track_);
    n_partial_ += f == Fused::kAcceptedPartial;
    consecutive_rejections_ = 0;
    candidate_ = Track{};
    ++n_updates_;
    return true;
  }
  refuse(refused_by(f));
  ++consecutive_rejections_;
  // A view that would have placed the centre elsewhere: the placements before it are in doubt.
  if (places_centre(track_, m)) track_.n_placed = 0;
  // The refused measurements as a track of their own: a candidate that refuses one in turn
  // starts over from it.
  if (!fused(fuse(candidate_, raw))) {
    candidate_ = Track{};
    fuse(candidate_, raw);
  }
  // Many in a row: the platform is not where the track believed. A believed track gives way
  // only to a candidate believed in turn (a burst of wrong measurements never replaces it).
  if (consecutive_rejections_ >= params_.max_consecutive_rejections &&
      (!believed(track_) || believed(candidate_))) {
    track_ = std::move(candidate_);
    candidate_ = Track{};
    consecutive_rejections_ = 0;
  }
  return false;
}

}  // namespace alight::autonomy
