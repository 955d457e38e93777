// Landing, a top without features found by its outline (see outline.hpp).
#include "vision/landing/outline.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "common/geometry.hpp"
#include "common/median.hpp"
#include "vision/geometry/bilinear.hpp"
#include "vision/landing/gates.hpp"

namespace alight::vision {
namespace {

/// The candidates' image: a quarter of the resolution (see outline.hpp, stage 1).
constexpr int kScale = 4;
/// The texture map's levels per grey level of standard deviation: a plain top's (the sensor's
/// noise, 4-6) and a busy floor's (8 and more) several MSER steps apart.
constexpr double kTextureScale = 8.0;
/// MSER's stability step on the texture map: 0.6 grey levels of standard deviation, about the
/// smoothed map's own noise over a plain top, an eighth of a busy floor's grain.
constexpr int kMserDelta = 5;
/// The smallest region measured [full-resolution px]: a top under about 40 px across gives
/// its centre to no better than the features' rectangle would.
constexpr double kMinAreaPx = 1500.0;
/// The least side of an outline measured, refined [full-resolution px], half the side of
/// kMinAreaPx's square: a plain region narrower is a stroke of the floor's pattern (a painted
/// line, a gap between boards), as plain as a top and as long, where a top to land on is several
/// times wider at any search height. The region's own width is no measure of it: the floor's
/// smooth grains that join a stroke's region at its rim widen it.
constexpr double kMinSidePx = 20.0;
/// A top's region fills the rectangle of its moments and lies in it, but for the floor's grains
/// joined at its rim and corners the quarter resolution rounds; a floor's blotch does not.
constexpr double kMinFill = 0.85;
/// Samples along each side (between 10 and 90 % of it, clear of the corners' rounding).
constexpr int kSideSamples = 16;
/// How far across a side its step is searched at full resolution [px]: the quarter-resolution
/// outline is within two of its pixels.
constexpr double kSearchPx = 8.0;
/// The refined corners stay within this of the candidate's [px]: farther, the lines fitted were
/// the floor's texture, not the outline.
constexpr double kMaxCornerMovePx = 3.0 * kScale;
/// A side's agreement over the heights has one peak: none this many grid steps away from it
/// reaches kMaxSecondPeak of it.
constexpr double kPeakWidthSteps = 3.0;
constexpr double kMaxSecondPeak = 0.8;
/// How far beyond a side its outside is read again [px]: past the rim's blur and a grout line.
constexpr double kFarPx = 8.0;
/// The least mean step across a side [grey levels], a rim's as the rim search takes it
/// (rim.cpp's kRimMinStep).
constexpr double kMinSideStep = 6.0;
/// A step across a side is read as the mean over this width either side of it [px].
constexpr double kStepWidthPx = 3.0;
/// The step across a side is read this far either side of it [px].
constexpr double kStepOffsetPx = 2.0;
/// The height search's grid, as how far it moves a side across itself a step [px], and how far
/// across a side the reference's rim is then sought [px]: the step read kStepOffsetPx either
/// side is seen from up to that far off the rim, and the grid's half step adds a pixel.
constexpr double kCoarseStepPx = 2.0;
constexpr double kCoarseSearchPx = 5.0;
/// A rectangle turned 45 degrees fills half its bounding box; under that, the region is a
/// floor's grains joined.
constexpr double kMinBoxFill = 0.45;
/// OpenCV's MSER leaves the image's outermost ring of pixels out of every region: a region the
/// border cuts ends this far inside it [quarter-resolution px].
constexpr int kMserRing = 1;
/// Regions whose centres lie this close are one region at several of MSER's thresholds [px].
constexpr double kSamePlacePx = 32.0;

Vector2d perp(const Vector2d& d) { return {-d.y(), d.x()}; }

/// The grey level at u averaged with its neighbours one pixel either way along `along`; false
/// outside the image.
bool grey_along(const cv::Mat& g, const Vector2d& u, const Vector2d& along, double* value) {
  double sum = 0;
  for (int s = -1; s <= 1; ++s) {
    double v = 0;
    if (!bilinear_inside(g, u + s * along, &v)) return false;
    sum += v;
  }
  *value = sum / 3.0;
  return true;
}

struct Line2 {
  Vector2d point, dir;
};

std::optional<Vector2d> meet(const Line2& a, const Line2& b) {
  const double den = a.dir.x() * b.dir.y() - a.dir.y() * b.dir.x();
  if (std::abs(den) < 1e-6) return std::nullopt;
  const Vector2d w = b.point - a.point;
  const double t = (w.x() * b.dir.y() - w.y() * b.dir.x()) / den;
  return a.point + t * a.dir;
}

/// Sample k of n along the side from a to b, between 10 and 90 % of it (clear of the
/// corners' rounding).
Vector2d side_sample(const Vector2d& a, const Vector2d& b, int k, int n = kSideSamples) {
  return a + (0.1 + 0.8 * k / (n - 1.0)) * (b - a);
}

Vector2d centroid(const std::vector<Vector2d>& q) {
  Vector2d m = Vector2d::Zero();
  for (const auto& p : q) m += p;
  return m / static_cast<double>(q.size());
}

/// Outward unit normal of side i (corner i to i + 1) of quadrilateral q.
Vector2d outward(const std::vector<Vector2d>& q, size_t i) {
  const Vector2d a = q[i], b = q[(i + 1) % 4];
  Vector2d n = perp((b - a).normalized());
  if (n.dot(0.5 * (a + b) - centroid(q)) < 0) n = -n;
  return n;
}

/// Whether the region is darker than what lies beyond its sides (their middles read 4 px in
/// and out).
bool darker_inside(const cv::Mat& g, const std::vector<Vector2d>& q) {
  double out_minus_in = 0;
  for (size_t i = 0; i < 4; ++i) {
    const Vector2d a = q[i], b = q[(i + 1) % 4];
    const Vector2d n = outward(q, i), d = (b - a).normalized();
    for (double t = 0.25; t < 0.8; t += 0.25) {
      const Vector2d u = a + t * (b - a);
      double in = 0, out = 0;
      if (grey_along(g, u - 4 * n, d, &in) && grey_along(g, u + 4 * n, d, &out))
        out_minus_in += out - in;
    }
  }
  return out_minus_in > 0;
}

/// Where along n, within +-search_px of u, the grey level steps most in the direction `sign`
/// (+1: brighter outward): the mean over kStepWidthPx beyond an offset less the mean over as
/// much before it (a busy floor's grain steps as much as the rim over a pixel or two, not over
/// a few: the top's side is plain), averaged a pixel either way along perp(n). The offset [px]
/// to the sub-pixel peak; nullopt where it never steps that way or the search leaves the image.
std::optional<double> strongest_step(const cv::Mat& g, const Vector2d& u, const Vector2d& n,
                                     double sign, double search_px) {
  const Vector2d along = perp(n);
  const int w = static_cast<int>(2 * kStepWidthPx);  // in half pixels
  const int n_off = static_cast<int>(4 * search_px) + 2 * w + 3;
  const double first = -search_px - 0.5 * (w + 1);
  std::vector<double> cum(static_cast<size_t>(n_off) + 1, 0.0);  // prefix sums of the profile
  for (int j = 0; j < n_off; ++j) {
    double v = 0;
    if (!grey_along(g, u + (first + 0.5 * j) * n, along, &v)) return std::nullopt;
    cum[static_cast<size_t>(j) + 1] = cum[static_cast<size_t>(j)] + v;
  }
  const auto mean = [&](int a, int b) {  // over profile samples [a, b)
    return (cum[static_cast<size_t>(b)] - cum[static_cast<size_t>(a)]) / (b - a);
  };
  std::vector<double> D(static_cast<size_t>(n_off), 0.0);
  int best = -1;
  double best_v = 0;
  for (int j = w + 1; j + w + 1 < n_off; ++j) {
    const double d = sign * (mean(j + 1, j + 1 + w) - mean(j - w, j));
    D[static_cast<size_t>(j)] = d;
    if (d > best_v) best_v = d, best = j;
  }
  if (best < 0) return std::nullopt;
  const size_t b = static_cast<size_t>(best);
  double off = first + 0.5 * best;
  if (best > w + 1 && best + w + 2 < n_off) {
    const double den = D[b - 1] - 2 * D[b] + D[b + 1];  // the parabola through the peak
    if (den < 0) off += 0.25 * (D[b - 1] - D[b + 1]) / den;
  }
  return off;
}

/// The line through points, robust to a few off it (Huber); nullopt under half of `expected`.
std::optional<Line2> fitted_line(const std::vector<cv::Point2f>& pts, size_t expected) {
  if (pts.size() < std::max<size_t>(2, expected / 2)) return std::nullopt;
  cv::Vec4f l;
  cv::fitLine(pts, l, cv::DIST_HUBER, 0, 0.01, 0.01);
  return Line2{Vector2d(l[2], l[3]), Vector2d(l[0], l[1])};
}

cv::Point2f to_cv(const Vector2d& u) {
  return {static_cast<float>(u.x()), static_cast<float>(u.y())};
}

}  // namespace

// Every sum is an integer a float holds exactly and the division is by a power of two: the
// integer sums give INTER_AREA's floats to the bit, without a float copy of the whole image and
// of its square.
void block_means(const cv::Mat& gray, const cv::Size& small, cv::Mat* mean, cv::Mat* mean_sq) {
  if (gray.cols != kScale * small.width || gray.rows != kScale * small.height) {
    cv::Mat f;
    gray.convertTo(f, CV_32F);
    cv::resize(f, *mean, small, 0, 0, cv::INTER_AREA);
    cv::resize(f.mul(f), *mean_sq, small, 0, 0, cv::INTER_AREA);
    return;
  }
  static_assert(kScale * kScale * 255 * 255 < (1 << 24), "a block's sum of squares is exact");
  constexpr float kPerPixel = 1.0f / (kScale * kScale);
  mean->create(small, CV_32F);
  mean_sq->create(small, CV_32F);
  std::vector<int32_t> sum(small.width), sum_sq(small.width);
  for (int by = 0; by < small.height; ++by) {
    std::fill(sum.begin(), sum.end(), 0);
    std::fill(sum_sq.begin(), sum_sq.end(), 0);
    for (int r = 0; r < kScale; ++r) {
      const uint8_t* g = gray.ptr<uint8_t>(by * kScale + r);
      for (int bx = 0; bx < small.width; ++bx)
        for (int c = 0; c < kScale; ++c) {
          const int32_t v = g[bx * kScale + c];
          sum[bx] += v;
          sum_sq[bx] += v * v;
        }
    }
    float* m = mean->ptr<float>(by);
    float* q = mean_sq->ptr<float>(by);
    for (int bx = 0; bx < small.width; ++bx) {
      m[bx] = static_cast<float>(sum[bx]) * kPerPixel;
      q[bx] = static_cast<float>(sum_sq[bx]) * kPerPixel;
    }
  }
}

namespace {

/// The image's local texture at the quarter resolution: the grey level's standard deviation
/// over a window a block either way of each kScale x kScale block (the blocks' means and mean
/// squares smoothed before they are differenced, so that the differences between blocks count),
/// in steps of an eighth of a grey level. Over a busy floor a top of one grey level is a plain
/// region of it where its mean grey need not stand out: the floor's dark grains are as dark as
/// the top. A grain larger than a block (a coarse floor seen close) varies little inside one,
/// as little as the sensor's noise varies a plain top in dim light, and shows only between
/// blocks.
cv::Mat texture_map(const cv::Mat& gray, const cv::Size& small) {
  cv::Mat mean, mean_sq;
  block_means(gray, small, &mean, &mean_sq);
  cv::GaussianBlur(mean, mean, cv::Size(0, 0), 1.0);
  cv::GaussianBlur(mean_sq, mean_sq, cv::Size(0, 0), 1.0);
  const cv::Mat var = cv::max(mean_sq - mean.mul(mean), 0.0);
  cv::Mat sd, out;
  cv::sqrt(var, sd);
  sd.convertTo(out, CV_8U, kTextureScale);
  return out;
}

/// The current image's matches counted on the quarter-resolution grid (an integral image), to
/// refuse a region with features in the middle half of its box at the cost of four reads.
class MatchGrid {
 public:
  MatchGrid(const Correspondences& c, const cv::Size& small)
      : sum_(small.height + 1, small.width + 1, CV_32S, cv::Scalar(0)) {
    cv::Mat count(small, CV_8U, cv::Scalar(0));
    for (const auto& u : c.u2) {
      const int x = static_cast<int>(u.x() / kScale), y = static_cast<int>(u.y() / kScale);
      if (x >= 0 && y >= 0 && x < small.width && y < small.height && count.at<uint8_t>(y, x) < 255)
        ++count.at<uint8_t>(y, x);
    }
    cv::integral(count, sum_, CV_32S);
  }
  int count_in_middle(const cv::Rect& box) const {
    const int x0 = box.x + box.width / 4, x1 = box.x + box.width - box.width / 4;
    const int y0 = box.y + box.height / 4, y1 = box.y + box.height - box.height / 4;
    return sum_.at<int>(y1, x1) - sum_.at<int>(y0, x1) - sum_.at<int>(y1, x0) +
           sum_.at<int>(y0, x0);
  }

 private:
  cv::Mat sum_;
};

/// Stage 3: each side to the line through its strongest step (the sign a dark or bright region
/// gives), the corners where the lines meet; nullopt where a side has too few steps or a corner
/// moves more than kMaxCornerMovePx.
std::optional<std::vector<Vector2d>> refined(const cv::Mat& g, const std::vector<Vector2d>& q,
                                             bool dark) {
  const double sign = dark ? 1.0 : -1.0;  // outward step: brighter beyond a dark region
  std::array<Line2, 4> lines;
  for (size_t i = 0; i < 4; ++i) {
    const Vector2d a = q[i], b = q[(i + 1) % 4];
    const Vector2d n = outward(q, i);
    std::vector<cv::Point2f> pts;
    for (int k = 0; k < kSideSamples; ++k) {
      const Vector2d u = side_sample(a, b, k);
      if (const auto off = strongest_step(g, u, n, sign, kSearchPx))
        pts.push_back(to_cv(u + *off * n));
    }
    const auto line = fitted_line(pts, kSideSamples);
    if (!line) return std::nullopt;
    lines[i] = *line;
  }
  std::vector<Vector2d> corners(4);
  for (size_t i = 0; i < 4; ++i) {
    const auto p = meet(lines[(i + 3) % 4], lines[i]);
    if (!p || (*p - q[i]).norm() > kMaxCornerMovePx) return std::nullopt;
    corners[i] = *p;
  }
  return corners;
}

/// The direction of a region's sides [rad, modulo a quarter turn]: the mean of four times the
/// angle of its outline's normals (the gradient of its mask smoothed over a pixel), weighted by
/// the gradient's strength, so that a rectangle's four sides agree whatever their lengths. The
/// second moments' axes are no such direction for a square (its moments are alike along every
/// direction), and for a nearly square top they follow the grains joined at its rim.
double side_direction(const std::vector<cv::Point>& region) {
  const cv::Rect box = cv::boundingRect(region);
  constexpr int kPad = 3;  // the smoothed mask's slope stays inside
  cv::Mat mask(box.height + 2 * kPad, box.width + 2 * kPad, CV_32F, cv::Scalar(0));
  for (const auto& p : region) mask.at<float>(p.y - box.y + kPad, p.x - box.x + kPad) = 1.0f;
  cv::GaussianBlur(mask, mask, cv::Size(0, 0), 1.0);
  cv::Mat gx, gy;
  cv::Sobel(mask, gx, CV_32F, 1, 0);
  cv::Sobel(mask, gy, CV_32F, 0, 1);
  double c4 = 0, s4 = 0;  // sum of |g| e^{4 i angle}: (gx + i gy)^4 / |g|^3
  for (int y = 0; y < mask.rows; ++y)
    for (int x = 0; x < mask.cols; ++x) {
      const double u = gx.at<float>(y, x), v = gy.at<float>(y, x), m2 = u * u + v * v;
      if (m2 < 1e-12) continue;
      const double re = u * u - v * v, im = 2 * u * v, m3 = m2 * std::sqrt(m2);
      c4 += (re * re - im * im) / m3;
      s4 += 2 * re * im / m3;
    }
  return 0.25 * std::atan2(s4, c4);
}

/// Stage 1's quadrilateral of one region clear of the border at the quarter resolution, in
/// full-resolution pixels; nullopt where the region is not a rectangle's (see outline.hpp).
std::optional<std::vector<Vector2d>> region_quad(const std::vector<cv::Point>& region) {
  // A level top under a camera that looks down is a rectangle in the image (a similarity of
  // it), kept near one by the vehicle's tilt. Its sides' direction from its outline
  // (side_direction), their lengths from the region's second moments along them (a uniform
  // rectangle's variance along a side of length a is a^2 / 12): the floor's dark grains that
  // join the region at its rim move them little, where they would widen the region's bounding
  // rectangle. The sides are refined at full resolution after.
  const double n = static_cast<double>(region.size());
  Vector2d mean = Vector2d::Zero();
  for (const auto& p : region) mean += Vector2d(p.x, p.y);
  mean /= n;
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& p : region) {
    const Vector2d d = Vector2d(p.x, p.y) - mean;
    cov += d * d.transpose();
  }
  cov /= n;
  // The fill test below needs kMinFill * 12 sigma_x sigma_y <= n along the sides found, and
  // sigma_x sigma_y >= sqrt(det(cov)) along any two perpendicular axes: a region that fails it
  // there fails it along every direction, refused before side_direction's filtering of its box
  // (a floor's grains joined in a sprawl, most of a busy image's regions). The margin keeps the
  // rounding of the two computations from refusing a region the full test would take.
  if (kMinFill * 12.0 * std::sqrt(std::max(cov.determinant(), 0.0)) > n * (1.0 + 1e-9))
    return std::nullopt;
  const double t = side_direction(region);
  Eigen::Matrix2d axes;
  axes << std::cos(t), -std::sin(t), std::sin(t), std::cos(t);
  const Vector2d half(std::sqrt(3.0 * std::max(axes.col(0).dot(cov * axes.col(0)), 0.0)),
                      std::sqrt(3.0 * std::max(axes.col(1).dot(cov * axes.col(1)), 0.0)));
  if (half.minCoeff() < 1.0) return std::nullopt;
  int inside = 0;
  for (const auto& p : region) {
    const Vector2d l = axes.transpose() * (Vector2d(p.x, p.y) - mean);
    if (std::abs(l.x()) <= half.x() + 0.5 && std::abs(l.y()) <= half.y() + 0.5) ++inside;
  }
  if (inside < kMinFill * n || inside < kMinFill * 4.0 * half.x() * half.y()) return std::nullopt;
  const Vector2d ex = half.x() * axes.col(0), ey = half.y() * axes.col(1);
  const std::array<Vector2d, 4> quad = {mean - ex - ey, mean + ex - ey, mean + ex + ey,
                                        mean - ex + ey};
  std::vector<Vector2d> q;
  // A quarter-resolution pixel x covers full pixels kScale x .. kScale x + kScale - 1.
  for (const auto& p : quad) q.push_back(kScale * p + Vector2d::Constant(0.5 * (kScale - 1)));
  return q;
}

double shortest_side(const std::vector<Vector2d>& q) {
  double s = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < q.size(); ++i) s = std::min(s, (q[(i + 1) % q.size()] - q[i]).norm());
  return s;
}

int matches_inside(const Correspondences& c, const std::vector<Vector2d>& q) {
  std::vector<cv::Point2f> poly;
  for (const auto& p : q) poly.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()));
  int n = 0;
  for (const auto& u : c.u2)
    if (cv::pointPolygonTest(
            poly, cv::Point2f(static_cast<float>(u.x()), static_cast<float>(u.y())), false) > 0)
      ++n;
  return n;
}

/// The plane z = z_m seen from camera 2 and projected into camera 1.
class PlaneMap {
 public:
  explicit PlaneMap(const Correspondences& c)
      : c_(c),
        X_WC1_(camera_in_world(c.pose_1.X_WB(), c.mount->X_BC())),
        X_WC2_(camera_in_world(c.pose_2.X_WB(), c.mount->X_BC())),
        X_C1W_(X_WC1_.inverse()) {}
  const Isometry3d& X_WC2() const { return X_WC2_; }
  /// World direction of camera 2's ray through raw pixel u.
  Vector3d dir_W(const Vector2d& u) const { return X_WC2_.linear() * c_.ray_of_pixel2(u); }
  /// Where the ray dir_W from camera 2 meets z = z_m; nullopt behind the camera.
  std::optional<Vector3d> on_plane(const Vector3d& dir_W, double z_m) const {
    return ray_at_height(X_WC2_.translation(), dir_W, z_m);
  }
  /// Camera 1's raw pixel of the point of z = z_m on the ray dir_W from camera 2.
  std::optional<Vector2d> to_1(const Vector3d& dir_W, double z_m) const {
    const auto P = on_plane(dir_W, z_m);
    if (!P) return std::nullopt;
    const Vector3d p_C1 = X_C1W_ * *P;
    if (!(p_C1.z() > 0)) return std::nullopt;
    return c_.pixel1(p_C1);
  }

 private:
  const Correspondences& c_;
  Isometry3d X_WC1_, X_WC2_, X_C1W_;
};

/// One point along a side: the rays just inside and outside it, and the current image's step.
struct SidePoint {
  Vector3d rim_W, in_W, out_W;
  double step = 0;  ///< current image, outward minus inward, signed so a region's rim is > 0
};

struct Side {
  std::vector<SidePoint> points;
  Vector3d mid_W, a_W, b_W;  ///< rays of its middle and its ends
  /// The current image's step from inside the side to kFarPx beyond it, summed over the points:
  /// a rim's outside stays unlike its inside; a line between two alike plains (a tile's grout,
  /// a plank's seam) returns to the inside's grey.
  double far_step = 0;
};

/// Each side of quadrilateral q from the current image g2: its kSideSamples points, their
/// steps (signed as a dark or bright region's rim) and the step kFarPx beyond.
std::array<Side, 4> sides_of(const std::vector<Vector2d>& q, const cv::Mat& g2, bool dark,
                             const PlaneMap& map) {
  const double sign = dark ? 1.0 : -1.0;
  std::array<Side, 4> sides;
  for (size_t i = 0; i < 4; ++i) {
    const Vector2d a = q[i], b = q[(i + 1) % 4];
    const Vector2d d = (b - a).normalized(), n = outward(q, i);
    Side& s = sides[i];
    s.mid_W = map.dir_W(0.5 * (a + b));
    s.a_W = map.dir_W(a);
    s.b_W = map.dir_W(b);
    for (int k = 0; k < kSideSamples; ++k) {
      const Vector2d u = side_sample(a, b, k);
      double in = 0, out = 0, far = 0;
      if (!grey_along(g2, u - kStepOffsetPx * n, d, &in) ||
          !grey_along(g2, u + kStepOffsetPx * n, d, &out) ||
          !grey_along(g2, u + kFarPx * n, d, &far))
        continue;
      s.points.push_back({map.dir_W(u), map.dir_W(u - kStepOffsetPx * n),
                          map.dir_W(u + kStepOffsetPx * n), sign * (out - in)});
      s.far_step += sign * (far - in);
    }
  }
  return sides;
}

/// The reference's step across side s at the plane z = z_m, summed over its points (signed as
/// the region's rim; a point the plane carries out of the reference adds nothing).
double reference_step(const Side& s, const cv::Mat& g1, const PlaneMap& map, double z_m,
                      double sign) {
  double ref = 0;
  for (const auto& p : s.points) {
    const auto in = map.to_1(p.in_W, z_m), out = map.to_1(p.out_W, z_m);
    if (!in || !out || (*out - *in).norm() < 1e-6) continue;
    const Vector2d along = perp((*out - *in).normalized());
    double gi = 0, go = 0;
    if (!grey_along(g1, *in, along, &gi) || !grey_along(g1, *out, along, &go)) continue;
    ref += sign * (go - gi);
  }
  return ref;
}

/// How far the planes z = z_a and z = z_b put side s's middle apart across the side, in the
/// reference [px]; 0 where either misses.
double side_parallax(const Side& s, const PlaneMap& map, double z_a, double z_b) {
  const auto ma = map.to_1(s.mid_W, z_a), mb = map.to_1(s.mid_W, z_b);
  const auto ea = map.to_1(s.a_W, z_a), eb = map.to_1(s.b_W, z_a);
  if (!ma || !mb || !ea || !eb || (*eb - *ea).norm() < 1e-6) return 0;
  return std::abs((*mb - *ma).dot(perp((*eb - *ea).normalized())));
}

/// One side's height above the floor z0, within [0, max_h]. The plane that carries the side's
/// step onto the reference best (the share of the current image's step the reference shows
/// there, on a grid moving the side kCoarseStepPx a step) is within about the step's reading
/// width (kStepOffsetPx) of the rim; the reference's own rim is then found across each carried
/// point (strongest_step) and fitted as a line, and each point's height is where its plane
/// carries it onto that line (the distance is linear in h over a few centimetres); the median
/// of the points' heights. `rate`: the median of how far the side moves across itself per
/// metre of height [px/m], which says how well its height is measured. nullopt for a side that
/// steps too little (kMinSideStep), whose outside returns to its inside's grey (a line), whose
/// agreement peaks twice (a repeated pattern), or whose rim the reference does not show; the
/// first three tell no height (*silent): the side itself, not the reference, says nothing.
struct SideHeight {
  double h = 0, agreement = 0, rate = 0;
  double on_floor = 0;  ///< the agreement the floor's plane gives (h = 0)
  /// A side above the floor stands out of it: the reference shows its step at h and not at
  /// the floor's plane, where the carried points lie beside the rim.
  bool stands_out() const { return agreement - on_floor >= kMinOutlineContrast; }
};

std::optional<SideHeight> side_height(const Side& s, const cv::Mat& g1, const PlaneMap& map,
                                      double z0, double max_h, double range_px, double sign,
                                      bool* silent) {
  *silent = true;
  double cur = 0;
  for (const auto& p : s.points) cur += p.step;
  // A side must step as a rim does (kMinSideStep on average, and as much kFarPx beyond it): a
  // weaker one is a floor's faint pattern, whose agreement at any height is its noise; one
  // whose outside returns to the inside's grey is a line between alike plains.
  if (s.points.empty() || cur < kMinSideStep * static_cast<double>(s.points.size()) ||
      s.far_step < kMinSideStep * static_cast<double>(s.points.size()))
    return std::nullopt;
  const auto share = [&](double h) { return reference_step(s, g1, map, z0 + h, sign) / cur; };
  double h_g = 0, best = -1e9;
  // The grid moves the side kCoarseStepPx across itself a step (range_px over max_h).
  const double step = max_h * kCoarseStepPx / std::max(range_px, kCoarseStepPx);
  std::vector<std::pair<double, double>> grid;  // (h, share)
  for (double h = 0; h <= max_h + 1e-9; h += step) {
    grid.emplace_back(h, share(h));
    if (grid.back().second > best) best = grid.back().second, h_g = h;
  }
  // One peak: a pattern that repeats across the side (tiles, planks) reads its step again one
  // period on, at another height; such a side tells no height.
  for (const auto& [h, a] : grid)
    if (std::abs(h - h_g) > kPeakWidthSteps * step && a >= kMaxSecondPeak * best)
      return std::nullopt;
  *silent = false;
  std::vector<cv::Point2f> edge;
  for (const auto& p : s.points) {
    const auto u = map.to_1(p.rim_W, z0 + h_g), in = map.to_1(p.in_W, z0 + h_g),
               out = map.to_1(p.out_W, z0 + h_g);
    if (!u || !in || !out || (*out - *in).norm() < 1e-6) continue;
    const Vector2d n1 = (*out - *in).normalized();
    if (const auto off = strongest_step(g1, *u, n1, sign, kCoarseSearchPx))
      edge.push_back(to_cv(*u + *off * n1));
  }
  const auto line = fitted_line(edge, s.points.size());
  if (!line) return std::nullopt;
  const Vector2d normal = perp(line->dir);
  constexpr double kDh = 0.01;  // [m]
  std::vector<double> hs, rates;
  for (const auto& p : s.points) {
    const auto a = map.to_1(p.rim_W, z0 + h_g), b = map.to_1(p.rim_W, z0 + h_g + kDh);
    if (!a || !b) continue;
    const double fa = (*a - line->point).dot(normal), fb = (*b - line->point).dot(normal);
    const double rate = (fb - fa) / kDh;
    if (std::abs(rate) < 1e-6) continue;
    hs.push_back(h_g - fa / rate);
    rates.push_back(std::abs(rate));
  }
  if (hs.size() < s.points.size() / 2 || hs.empty()) return std::nullopt;
  SideHeight r;
  r.h = std::clamp(upper_median(hs), 0.0, max_h);
  r.rate = upper_median(rates);
  r.agreement = share(r.h);
  r.on_floor = share(0.0);
  return r;
}

/// A side along the camera's motion has no parallax to say whether the outline there is the
/// rim or the foot of a side face. A side face is seen from outside it only; lit from above it
/// is darker than the top, so it belongs to a dark top's region (whose outline is then the
/// face's foot) and not to a bright one's (whose outline stays the rim).
bool face_in_region(const Outline& o, size_t i, const PlaneMap& map, double z_top) {
  if (!o.dark) return false;
  const auto a = map.on_plane(map.dir_W(o.corners[i]), z_top);
  const auto b = map.on_plane(map.dir_W(o.corners[(i + 1) % 4]), z_top);
  Vector3d centre = Vector3d::Zero();
  for (const auto& u : o.corners) {
    const auto p = map.on_plane(map.dir_W(u), z_top);
    if (!p || !a || !b) return false;
    centre += 0.25 * *p;
  }
  const Vector2d d = (*b - *a).head<2>();
  Vector2d n(-d.y(), d.x());
  if (n.dot((0.5 * (*a + *b) - centre).head<2>()) < 0) n = -n;
  return n.dot((map.X_WC2().translation() - *a).head<2>()) > 0;
}

/// The top's corners at z_top: each side's line where its rays meet z = side_z[i] (on the side
/// face below the rim where that is under z_top: the face stands vertical), the corners where
/// adjacent lines meet. False where a ray misses its plane or two lines are parallel.
bool top_corners(const Outline& o, const std::array<double, 4>& side_z, const PlaneMap& map,
                 double z_top, std::array<Vector3d, 4>* P) {
  std::array<Line2, 4> lines;
  for (size_t i = 0; i < 4; ++i) {
    const auto a = map.on_plane(map.dir_W(o.corners[i]), side_z[i]);
    const auto b = map.on_plane(map.dir_W(o.corners[(i + 1) % 4]), side_z[i]);
    if (!a || !b || (*b - *a).head<2>().norm() < 1e-9) return false;
    lines[i] = {a->head<2>(), (*b - *a).head<2>().normalized()};
  }
  for (size_t i = 0; i < 4; ++i) {
    const auto p = meet(lines[(i + 3) % 4], lines[i]);
    if (!p) return false;
    (*P)[i] = Vector3d(p->x(), p->y(), z_top);
  }
  return true;
}

/// The top's height (stage 4): the largest set of sides that stand out of the floor and agree
/// within kAgreePx on a height above min_height_m, the higher on a tie, each weighted by its
/// rate squared (the inverse of its height's variance). The other sides lie lower on a side
/// face (its foot, or a line between foot and rim where the face is narrower than the step's
/// reading). kOutlineOnFloor where no side stands out above the floor, kOutlineUnmatched where
/// fewer than two agree (one side's chance agreement over a busy floor is no top),
/// kHeightOutOfRange above max_height_m.
Result<double> top_height(const std::array<std::optional<SideHeight>, 4>& heights,
                          const LandingParams& L) {
  double h = -1, best_w = 0;
  int best_n = 0;
  const auto counts = [&](const std::optional<SideHeight>& s) {
    return s && s->h >= L.min_height_m && s->stands_out();
  };
  for (const auto& c : heights) {
    if (!counts(c)) continue;
    double sum = 0, w = 0;
    int n = 0;
    for (const auto& s : heights)
      if (counts(s) && std::abs(s->h - c->h) * s->rate <= kAgreePx)
        sum += s->rate * s->rate * s->h, w += s->rate * s->rate, ++n;
    if (w > best_w * (1 + 1e-9) || (w >= best_w * (1 - 1e-9) && sum / w > h))
      best_w = w, h = sum / w, best_n = n;
  }
  if (h < 0) return Result<double>::fail(Reason::kOutlineOnFloor);
  if (best_n < 2) return Result<double>::fail(Reason::kOutlineUnmatched);
  if (!height_in_range(h, L)) return Result<double>::fail(Reason::kHeightOutOfRange);
  return Result<double>::ok(h);
}

/// A side face's points next to its rim lie within a few centimetres of the top's height, where
/// the plane z_top carries them within the homography's threshold: seen from 1-2 m, the band of
/// a face that close to the rim spans up to about 10 px of the image beside the outline.
constexpr double kFaceBandPx = 12.0;

/// A print on a larger top (a dark panel of a photograph, a painted square) has an outline of
/// its own at the top's height, and a top of the same grain as its floor may show little else:
/// the top runs on past it. The matches beyond the outline by kFaceBandPx or more, and within
/// its own longer side of it, that the plane z = z_top carries onto their reference pixel
/// (within tol_px) while the floor's plane puts them at least twice that far off: the top's own
/// points past the outline (a side face's lie below z_top, a floor's on z_floor). Their count;
/// one is enough (a floor match fits z_top by chance only where it was mismatched to a pixel
/// the floor's parallax does not explain).
int top_matches_beyond(const Outline& o, const Correspondences& c, const PlaneMap& map,
                       double z_top, double z_floor, double tol_px) {
  std::vector<cv::Point2f> poly;
  double reach_px = 0;
  for (size_t i = 0; i < 4; ++i) {
    poly.push_back(to_cv(o.corners[i]));
    reach_px = std::max(reach_px, (o.corners[(i + 1) % 4] - o.corners[i]).norm());
  }
  int n = 0;
  for (size_t k = 0; k < c.size(); ++k) {
    const double inside = cv::pointPolygonTest(poly, to_cv(c.u2[k]), true);
    if (inside > -kFaceBandPx || -inside > reach_px) continue;
    const Vector3d dir = map.X_WC2().linear() * c.ray2(k);
    const auto on_top = map.to_1(dir, z_top), on_floor = map.to_1(dir, z_floor);
    if (on_top && (*on_top - c.u1[k]).norm() <= tol_px &&
        (!on_floor || (*on_floor - c.u1[k]).norm() >= 2 * tol_px))
      ++n;
  }
  return n;
}

/// Where the image just beyond a side is read for its motion [px past the outline]: past the
/// band of a side face next to the rim (kFaceBandPx), three rows 3 px apart.
constexpr double kOutsideOffsetPx = kFaceBandPx + 2.0;
constexpr int kOutsideRows = 3;
constexpr double kOutsideRowStepPx = 3.0;
/// The outside must vary along the side for its motion to be read: a plain floor beside a top,
/// or a plain top beside a print, reads alike on both planes [grey levels, standard deviation].
constexpr double kMinOutsideTexture = 6.0;
/// The outside moves with the top where the top's plane carries it onto the reference with this
/// correlation, and leaves at most this share of what the floor's plane leaves uncorrelated: a
/// rim's outside is the floor, seen through a parallax of several pixels at least
/// (kMinSideParallaxPx), which no texture of that scale survives unchanged; a smooth one changes
/// little, but less under the plane it lies in.
constexpr double kMinOutsideCorrelation = 0.6;
constexpr double kMaxOutsideResidualShare = 0.5;

/// Pearson's correlation of a and b; 0 where either is flat (cv::matchTemplate's
/// TM_CCOEFF_NORMED gives 1 for a flat template, which would read a plain outside as moving).
double correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const double n = static_cast<double>(a.size());
  double ma = 0, mb = 0;
  for (size_t k = 0; k < a.size(); ++k) {
    ma += a[k];
    mb += b[k];
  }
  ma /= n;
  mb /= n;
  double sab = 0, saa = 0, sbb = 0;
  for (size_t k = 0; k < a.size(); ++k) {
    sab += (a[k] - ma) * (b[k] - mb);
    saa += (a[k] - ma) * (a[k] - ma);
    sbb += (b[k] - mb) * (b[k] - mb);
  }
  return saa > 0 && sbb > 0 ? sab / std::sqrt(saa * sbb) : 0.0;
}

/// Stage 6, by the outline's own sides: how many sides' outsides (read beyond a side face's
/// band) the plane z_top carries onto the reference, and the floor's does not. A print's
/// outside is the top it is printed on; a top's is the floor, below it.
int sides_with_top_outside(const Outline& o, const cv::Mat& gray_1, const cv::Mat& gray_2,
                           const PlaneMap& map, double z_top, double z_floor) {
  int n = 0;
  for (size_t i = 0; i < 4; ++i) {
    const Vector2d a = o.corners[i], b = o.corners[(i + 1) % 4];
    const Vector2d nrm = outward(o.corners, i);
    std::vector<double> v2, v_top, v_floor;
    for (int r = 0; r < kOutsideRows; ++r)
      for (int k = 0; k < 2 * kSideSamples; ++k) {
        const Vector2d u = side_sample(a, b, k, 2 * kSideSamples) +
                           (kOutsideOffsetPx + r * kOutsideRowStepPx) * nrm;
        const Vector3d dir = map.dir_W(u);
        const auto u_top = map.to_1(dir, z_top), u_floor = map.to_1(dir, z_floor);
        double g2 = 0, g_top = 0, g_floor = 0;
        if (!u_top || !u_floor || !bilinear_inside(gray_2, u, &g2) ||
            !bilinear_inside(gray_1, *u_top, &g_top) ||
            !bilinear_inside(gray_1, *u_floor, &g_floor))
          continue;
        v2.push_back(g2);
        v_top.push_back(g_top);
        v_floor.push_back(g_floor);
      }
    if (v2.size() < static_cast<size_t>(kOutsideRows * kSideSamples)) continue;  // half unseen
    cv::Scalar mean, sd;
    cv::meanStdDev(v2, mean, sd);
    if (sd[0] < kMinOutsideTexture) continue;
    const double c_top = correlation(v2, v_top), c_floor = correlation(v2, v_floor);
    n += c_top >= kMinOutsideCorrelation &&
         1.0 - c_top <= kMaxOutsideResidualShare * (1.0 - c_floor);
  }
  return n;
}

/// The target (stage 5) of the top whose corners at height h are P: centre, sides (long
/// first), heading of the long sides, the outline; kPartialView where a corner lies within
/// edge_margin_px of the image's border.
TargetOutcome top_estimate(const Outline& o, const std::array<Vector3d, 4>& P, double h,
                           const Correspondences& c, const PlaneMap& map, const LandingParams& L) {
  TargetOutcome out;
  TargetEstimate& e = out.estimate;
  e.p_W = 0.25 * (P[0] + P[1] + P[2] + P[3]);
  e.n_W = Vector3d::UnitZ();
  e.height_m = h;
  const double s0 = 0.5 * ((P[1] - P[0]).norm() + (P[2] - P[3]).norm());
  const double s1 = 0.5 * ((P[2] - P[1]).norm() + (P[3] - P[0]).norm());
  const Vector3d along = s0 >= s1 ? (P[1] - P[0]) + (P[2] - P[3]) : (P[2] - P[1]) + (P[3] - P[0]);
  e.size_m[0] = std::max(s0, s1);
  e.size_m[1] = std::min(s0, s1);
  e.yaw_rad = wrap_axis_angle(std::atan2(along.y(), along.x()));
  e.outline = o.corners;
  const auto px = c.pixel2(map.X_WC2().inverse() * e.p_W);
  e.pixel = px ? *px : centroid(o.corners);
  const auto near_border = [&](const Vector2d& u) {
    return u.x() < L.edge_margin_px || u.y() < L.edge_margin_px ||
           u.x() > c.camera->width - 1 - L.edge_margin_px ||
           u.y() > c.camera->height - 1 - L.edge_margin_px;
  };
  out.reason = std::any_of(o.corners.begin(), o.corners.end(), near_border) ? Reason::kPartialView
                                                                            : Reason::kOk;
  return out;
}

TargetOutcome refuse(Reason r) {
  TargetOutcome out;
  out.reason = r;
  return out;
}

}  // namespace

std::pair<double, double> height_search_range(const std::function<double(double)>& parallax_px,
                                              double max_h, double diag_px) {
  const double range_px = parallax_px(max_h);
  if (range_px <= diag_px) return {max_h, range_px};
  double lo = 0, hi = max_h;
  for (int k = 0; k < 40; ++k) {
    const double mid = 0.5 * (lo + hi);
    (parallax_px(mid) <= diag_px ? lo : hi) = mid;
  }
  return {lo, parallax_px(lo)};
}

const PlainRegions::Found& PlainRegions::found() const {
  if (found_) return *found_;
  found_.emplace();
  Found& f = *found_;
  if (gray_.empty() || gray_.type() != CV_8UC1 || gray_.cols < 8 * kScale ||
      gray_.rows < 8 * kScale)
    return f;
  f.small = cv::Size(gray_.cols / kScale, gray_.rows / kScale);
  const auto mser = cv::MSER::create(kMserDelta, static_cast<int>(kMinAreaPx / (kScale * kScale)),
                                     f.small.area() / 2);
  // The plain regions alone (stage 1): the dark ones of the texture map are found by MSER's
  // pass over the image's inverse, and its second pass inverts what it is given, so it is given
  // the map inverted and told to make that pass only.
  mser->setPass2Only(true);
  cv::Mat inverted;
  cv::subtract(cv::Scalar::all(255), texture_map(gray_, f.small), inverted);
  mser->detectRegions(inverted, f.regions, f.boxes);
  // Largest first; MSER gives one region at several thresholds: one candidate per place.
  f.largest_first.resize(f.regions.size());
  for (size_t i = 0; i < f.largest_first.size(); ++i) f.largest_first[i] = i;
  std::sort(f.largest_first.begin(), f.largest_first.end(),
            [&](size_t a, size_t b) { return f.regions[a].size() > f.regions[b].size(); });
  memo_.resize(f.regions.size());
  return f;
}

const std::optional<std::vector<Vector2d>>& PlainRegions::quad(size_t i) const {
  const Found& f = found();
  assert(i < f.regions.size());
  if (!memo_[i].quad) memo_[i].quad = region_quad(f.regions[i]);
  return *memo_[i].quad;
}

const std::optional<Outline>& PlainRegions::outline(size_t i) const {
  const auto& q = quad(i);  // the regions found first
  if (!memo_[i].outline) {
    std::optional<Outline> o;
    if (q) {
      const bool dark = darker_inside(gray_, *q);
      if (auto r = refined(gray_, *q, dark); r && shortest_side(*r) >= kMinSidePx)
        o = Outline{std::move(*r), dark};
    }
    memo_[i].outline = std::move(o);
  }
  return *memo_[i].outline;
}

std::vector<Outline> featureless_outlines(const cv::Mat& gray, const Correspondences& c,
                                          const PipelineParams& params, size_t max_outlines) {
  return featureless_outlines(PlainRegions(gray), c, params, max_outlines);
}

std::vector<Outline> featureless_outlines(const PlainRegions& plain, const Correspondences& c,
                                          const PipelineParams& params, size_t max_outlines) {
  std::vector<Outline> found;
  const PlainRegions::Found& f = plain.found();
  if (f.regions.empty()) return found;
  const cv::Size& small = f.small;
  const auto& regions = f.regions;
  const auto& boxes = f.boxes;
  std::vector<size_t> quads;  // regions with a rectangle
  const MatchGrid grid(c, small);
  std::vector<Vector2d> places;  // the box centres of the regions taken, at quarter resolution
  for (size_t i : f.largest_first) {
    if (quads.size() == 2 * max_outlines) break;
    const cv::Rect& box = boxes[i];
    // Cheap refusals first (a busy image has hundreds of regions): a region that fills under
    // kMinBoxFill of its box is no rectangle's in any turn; one with features in the middle of
    // its box is not featureless; one where a larger was taken is that region at another of
    // MSER's thresholds; one touching the border is cut by it (its outline there the border's).
    const Vector2d place(box.x + 0.5 * box.width, box.y + 0.5 * box.height);
    if (static_cast<double>(regions[i].size()) < kMinBoxFill * box.area() ||
        grid.count_in_middle(box) >= params.landing.min_platform_inliers / 2 ||
        std::any_of(
            places.begin(), places.end(),
            [&](const Vector2d& p) { return (p - place).norm() * kScale < kSamePlacePx; }) ||
        box.x <= kMserRing || box.y <= kMserRing || box.br().x >= small.width - kMserRing ||
        box.br().y >= small.height - kMserRing)
      continue;
    if (plain.quad(i)) {
      quads.push_back(i);
      places.push_back(place);
    }
  }
  for (size_t i : quads) {
    if (found.size() == max_outlines) break;
    if (matches_inside(c, *plain.quad(i)) >= params.landing.min_platform_inliers) continue;
    if (const auto& o = plain.outline(i)) found.push_back(*o);
  }
  return found;
}

TargetOutcome top_of_outline(const Outline& o, const Correspondences& c, const cv::Mat& gray_1,
                             const cv::Mat& gray_2, const PipelineParams& params) {
  assert(c.camera && c.mount && o.corners.size() == 4);
  const LandingParams& L = params.landing;
  const PlaneMap map(c);
  const double sign = o.dark ? 1.0 : -1.0, z0 = L.floor_z_m;
  const std::array<Side, 4> sides = sides_of(o.corners, gray_2, o.dark, map);
  // Stage 4: each side that can tell a top within range from the floor, at its own height.
  std::array<std::optional<SideHeight>, 4> heights;
  int informative = 0;
  const double diag_px = std::hypot(c.camera->width, c.camera->height);
  for (size_t i = 0; i < 4; ++i)
    if (const auto [max_h, range_px] =
            height_search_range([&](double h) { return side_parallax(sides[i], map, z0, z0 + h); },
                                L.max_height_m, diag_px);
        range_px >= kMinSideParallaxPx) {
      ++informative;
      // A side that tells no height (too faint a step: a dim top on a dark floor; a pattern
      // repeated across it) is left out, the top standing on the others (two must agree:
      // top_height). One the reference does not show, or shows at no height with its step,
      // refuses the outline.
      bool silent = false;
      heights[i] = side_height(sides[i], gray_1, map, z0, max_h, range_px, sign, &silent);
      if ((!heights[i] && !silent) || (heights[i] && heights[i]->agreement < kMinOutlineAgreement))
        return refuse(Reason::kOutlineUnmatched);
    }
  if (informative < 2) return refuse(Reason::kSmallBaseline);
  // Not one side tells a height (in dim light a top's step on a busy floor sinks under the
  // noise): nothing places the outline, neither on the floor nor above it.
  if (std::none_of(heights.begin(), heights.end(), [](const auto& s) { return s.has_value(); }))
    return refuse(Reason::kOutlineSilent);
  const auto top = top_height(heights, L);
  if (!top) return refuse(top.reason());
  const double h = top.value();
  // Stage 5: each side's line at its own height: a side face stands vertical, so a line on it
  // (its foot, the rim, or between) lies over the rim. A side that moves under
  // kMinSideParallaxPx between the floor and the top cannot say where on the face it is.
  std::array<double, 4> side_z{};
  int rims = 0;
  for (size_t i = 0; i < 4; ++i) {
    if (heights[i] && heights[i]->rate * h >= kMinSideParallaxPx) {
      side_z[i] = z0 + std::min(heights[i]->h, h);
      if (std::abs(heights[i]->h - h) * heights[i]->rate <= kAgreePx) ++rims;
    } else {
      side_z[i] = face_in_region(o, i, map, z0 + h) ? z0 : z0 + h;
    }
  }
  if (rims == 0) return refuse(Reason::kSmallBaseline);
  std::array<Vector3d, 4> P;
  if (!top_corners(o, side_z, map, z0 + h, &P)) return refuse(Reason::kCornerOffPlane);
  TargetOutcome out = top_estimate(o, P, h, c, map, L);
  // No gear stands on a top narrower than itself, whatever the region is; on a coarse floor a
  // patch of the pattern that a chance agreement of its grains placed above the floor is such a
  // region. It is whole in view (stage 1 leaves out regions the border cuts): its width is
  // measured, not a lower bound.
  if (out.estimate.size_m[1] < L.gear_footprint_m) {
    out.reason = Reason::kTopTooSmall;
    return out;
  }
  if (out.reason == Reason::kOk &&
      (top_matches_beyond(o, c, map, z0 + h, z0, params.homography.threshold_px) > 0 ||
       sides_with_top_outside(o, gray_1, gray_2, map, z0 + h, z0) > 0))
    out.reason = Reason::kTopRunsOn;
  return out;
}

int corners_on_floor(const Outline& o, const Correspondences& c, const std::vector<Label>& labels) {
  int n = 0;
  for (const auto& q : o.corners)
    for (size_t k = 0; k < c.size() && k < labels.size(); ++k)
      if (labels[k] == Label::kDominant && (c.u2[k] - q).norm() <= kCornerFeaturePx) {
        ++n;
        break;
      }
  return n;
}

std::optional<TargetOutcome> find_outline_top(const Correspondences& c,
                                              const std::vector<Label>& labels,
                                              const cv::Mat& gray_1, const cv::Mat& gray_2,
                                              const PipelineParams& params,
                                              const PlainRegions* regions_2) {
  const PlainRegions own(regions_2 ? cv::Mat() : gray_2);
  const std::vector<Outline> outlines =
      featureless_outlines(regions_2 ? *regions_2 : own, c, params);
  if (outlines.empty()) return std::nullopt;
  std::optional<TargetOutcome> first;
  for (const auto& o : outlines) {
    TargetOutcome t = corners_on_floor(o, c, labels) >= 2
                          ? refuse(Reason::kOutlineOnFloor)
                          : top_of_outline(o, c, gray_1, gray_2, params);
    if (t.reason == Reason::kOk || t.reason == Reason::kPartialView) return t;
    if (!first) first = std::move(t);
  }
  return first;
}

}  // namespace alight::vision
