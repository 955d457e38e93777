// The smooth gain between two views of one plane; see plane_gain.hpp.
#include "vision/geometry/plane_gain.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <cmath>

#include "common/median.hpp"

namespace alight::vision {
namespace {

using Row6 = Eigen::Matrix<double, 1, 6>;

// The local means' half-window at full size [px]: wide enough that a homography a pixel off
// moves a textured window's mean by a few percent of its contrast, narrow enough to stay on the
// plane near its border.
constexpr double kHalfWindowPx = 7.0;
// A window darker than this [grey levels] has no gain to measure (noise and the black level);
// one brighter than this may be clipped.
constexpr double kMinLevel = 12.0;
constexpr double kMaxLevel = 245.0;
// The robust fit: points beyond kRejectSigmas robust sigmas of the log ratio (but never within
// kMinRejectLog, 2 %) are dropped and the model fitted again to the rest, kRounds times.
constexpr double kRejectSigmas = 3.0;
constexpr double kMinRejectLog = 0.02;
constexpr int kRounds = 3;
// The quadratic is kept over the constant where the F statistic of the five extra terms exceeds
// this: F(5, n - 6)'s 1 % point is 3.0-3.7 for the 24 to several hundred points a view holds.
constexpr double kMinFalloffF = 4.0;

Row6 basis(double x, double y) {
  Row6 b;
  b << 1.0, x, y, x * x, x * y, y * y;
  return b;
}

// The mean over the (2h + 1)^2 window centred at the pixel nearest (u, v); nullopt when it
// leaves the image.
std::optional<double> window_mean(const cv::Mat& image, double u, double v, int h) {
  const int uc = static_cast<int>(std::lround(u)), vc = static_cast<int>(std::lround(v));
  if (!(uc - h >= 0 && vc - h >= 0 && uc + h < image.cols && vc + h < image.rows))
    return std::nullopt;
  int sum = 0;
  for (int y = vc - h; y <= vc + h; ++y) {
    const uint8_t* row = image.ptr<uint8_t>(y);
    for (int x = uc - h; x <= uc + h; ++x) sum += row[x];
  }
  return static_cast<double>(sum) / ((2 * h + 1) * (2 * h + 1));
}

struct Samples {
  std::vector<Row6> rows;  // the basis at each point
  std::vector<double> log_ratio;
};

// The log ratio of the local means at each plane point seen with both windows inside their
// images and at a measurable level.
Samples sample_ratios(const cv::Mat& image, const cv::Mat& reference, double scale,
                      const Matrix3d& H_21, const CameraModel& camera,
                      const std::vector<Vector2d>& plane_px) {
  const Matrix3d K = camera.K(), K_inv = K.inverse(), H_12 = H_21.inverse();
  const int h = std::max(2, static_cast<int>(std::lround(kHalfWindowPx / scale)));
  const auto small = [scale](double u_full) { return (u_full + 0.5) / scale - 0.5; };
  Samples s;
  for (const Vector2d& u2 : plane_px) {
    if (!u2.allFinite() || !camera.in_image(u2)) continue;
    const Vector3d r1 = K_inv * (H_12 * (K * camera.ray(u2)));
    if (!(r1.z() > 0)) continue;
    const auto u1 = camera.project(r1);
    if (!u1) continue;
    const auto m2 = window_mean(image, small(u2.x()), small(u2.y()), h);
    const auto m1 = window_mean(reference, small(u1->x()), small(u1->y()), h);
    if (!m1 || !m2 || *m1 < kMinLevel || *m2 < kMinLevel || *m1 > kMaxLevel || *m2 > kMaxLevel)
      continue;
    s.rows.push_back(basis((u2.x() - K(0, 2)) / K(0, 0), (u2.y() - K(1, 2)) / K(1, 1)));
    s.log_ratio.push_back(std::log(*m2 / *m1));
  }
  return s;
}

// Least squares over the kept points: the full quadratic where enough points support it and it
// is well posed, else the constant term alone.
Eigen::Matrix<double, 6, 1> fit(const Samples& s, const std::vector<char>& keep, int n_keep,
                                bool quadratic) {
  Eigen::Matrix<double, 6, 1> c = Eigen::Matrix<double, 6, 1>::Zero();
  if (quadratic && n_keep >= kMinPointsQuadratic) {
    Eigen::MatrixXd A(n_keep, 6);
    Eigen::VectorXd b(n_keep);
    for (size_t i = 0, k = 0; i < s.rows.size(); ++i)
      if (keep[i]) A.row(k) = s.rows[i], b(k++) = s.log_ratio[i];
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
    if (qr.rank() == 6) return qr.solve(b);
  }
  std::vector<double> kept;
  for (size_t i = 0; i < s.rows.size(); ++i)
    if (keep[i]) kept.push_back(s.log_ratio[i]);
  c(0) = upper_median(kept);
  return c;
}

// Whether the quadratic c explains the kept points' ratios better than their mean by more than
// its five extra terms explain noise: the nested models' F statistic above kMinFalloffF. A few
// dozen points of textured windows, a few percent apart each, otherwise give a quadratic that
// swings by 10-20 % across a view without any falloff.
bool falloff_is_plain(const Samples& s, const std::vector<char>& keep,
                      const Eigen::Matrix<double, 6, 1>& c) {
  if (c.tail<5>().isZero()) return false;
  double sum = 0, rss_quadratic = 0;
  int n = 0;
  for (size_t i = 0; i < s.rows.size(); ++i)
    if (keep[i]) {
      sum += s.log_ratio[i];
      rss_quadratic += std::pow(s.log_ratio[i] - s.rows[i].dot(c), 2);
      ++n;
    }
  if (n <= 6) return false;
  double rss_mean = 0;
  for (size_t i = 0; i < s.rows.size(); ++i)
    if (keep[i]) rss_mean += std::pow(s.log_ratio[i] - sum / n, 2);
  if (rss_quadratic <= 0) return rss_mean > 0;
  const double f = ((rss_mean - rss_quadratic) / 5.0) / (rss_quadratic / (n - 6));
  return f > kMinFalloffF;
}

}  // namespace

double PlaneGain::log_gain(double x, double y) const {
  return std::clamp(basis(x, y).dot(c), log_min, log_max);
}

std::optional<PlaneGain> fit_plane_gain(const cv::Mat& image, const cv::Mat& reference,
                                        double scale, const Matrix3d& H_21,
                                        const CameraModel& camera,
                                        const std::vector<Vector2d>& plane_px) {
  assert(image.type() == CV_8UC1 && reference.type() == CV_8UC1 && scale > 0);
  const Samples s = sample_ratios(image, reference, scale, H_21, camera, plane_px);
  const int n = static_cast<int>(s.rows.size());
  if (n < kMinPointsConstant) return std::nullopt;
  std::vector<char> keep(n, 1);
  int n_keep = n;
  PlaneGain g;
  // The first round fits the median alone: a quadratic fitted to every point can bend towards
  // a cluster of points off the plane (an opening in the middle of the view) and keep it.
  for (int round = 0; round < kRounds; ++round) {
    g.c = fit(s, keep, n_keep, round > 0);
    std::vector<double> residual(n);
    for (int i = 0; i < n; ++i) residual[i] = std::abs(s.log_ratio[i] - s.rows[i].dot(g.c));
    const double limit = std::max(kMinRejectLog, kRejectSigmas * 1.4826 * upper_median(residual));
    int kept = 0;
    for (int i = 0; i < n; ++i) kept += residual[i] <= limit;
    if (kept < kMinPointsConstant) break;  // keep the last fit's points
    for (int i = 0; i < n; ++i) keep[i] = residual[i] <= limit;
    n_keep = kept;
  }
  g.c = fit(s, keep, n_keep, true);
  if (!falloff_is_plain(s, keep, g.c)) g.c = fit(s, keep, n_keep, false);
  g.n_used = n_keep;
  g.log_min = g.log_max = s.rows[0].dot(g.c);
  bool first = true;
  for (int i = 0; i < n; ++i) {
    if (!keep[i]) continue;
    const double f = s.rows[i].dot(g.c);
    g.log_min = first ? f : std::min(g.log_min, f);
    g.log_max = first ? f : std::max(g.log_max, f);
    first = false;
  }
  return g;
}

cv::Mat remove_gain(const cv::Mat& image, double scale, const CameraModel& camera,
                    const PlaneGain& gain) {
  assert(image.type() == CV_8UC1 && scale > 0);
  const Matrix3d K = camera.K();
  const float ax = static_cast<float>(scale / K(0, 0));
  const float bx = static_cast<float>((0.5 * scale - 0.5 - K(0, 2)) / K(0, 0));
  const float ay = static_cast<float>(scale / K(1, 1));
  const float by = static_cast<float>((0.5 * scale - 0.5 - K(1, 2)) / K(1, 1));
  const auto c = gain.c.cast<float>();
  const float lo = static_cast<float>(-gain.log_max), hi = static_cast<float>(-gain.log_min);
  cv::Mat out(image.size(), CV_8UC1);
  cv::Mat inv_gain(1, image.cols, CV_32F);  // one row at a time: 1 / gain
  float* ig = inv_gain.ptr<float>();
  for (int v = 0; v < image.rows; ++v) {
    const float y = ay * v + by;
    // Along a row the log gain is a quadratic in x: c0' + c1' x + c3 x^2.
    const float r0 = c(0) + c(2) * y + c(5) * y * y, r1 = c(1) + c(4) * y, r2 = c(3);
    for (int u = 0; u < image.cols; ++u) {
      const float x = ax * u + bx;
      ig[u] = std::clamp(-(r0 + (r1 + r2 * x) * x), lo, hi);
    }
    cv::exp(inv_gain, inv_gain);
    const uint8_t* in = image.ptr<uint8_t>(v);
    uint8_t* o = out.ptr<uint8_t>(v);
    for (int u = 0; u < image.cols; ++u)
      o[u] = static_cast<uint8_t>(std::min(255.0f, in[u] * ig[u] + 0.5f));
  }
  return out;
}

}  // namespace alight::vision
