// Ingress target, paper 3.3 (see ingress_target.hpp).
#include "vision/ingress/ingress_target.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <utility>

#include "vision/geometry/decomposition.hpp"
#include "vision/geometry/homography.hpp"
#include "vision/geometry/warp_diff.hpp"
#include "vision/geometry/waypoint.hpp"
#include "vision/ingress/mask_border.hpp"

namespace alight::vision {
namespace {

std::vector<double> merged(std::vector<double> v, double merge_px) {
  std::sort(v.begin(), v.end());
  std::vector<double> out;
  for (double x : v) {
    if (!out.empty() && x - out.back() <= merge_px) continue;  // keep the first of a cluster
    out.push_back(x);
  }
  return out;
}

int cell_of(const std::vector<double>& cuts, double x) {
  const auto it = std::upper_bound(cuts.begin(), cuts.end(), x);
  const int i = static_cast<int>(it - cuts.begin()) - 1;
  return std::clamp(i, 0, static_cast<int>(cuts.size()) - 2);
}

// The point nearest both rays c_a + s d_a and c_b + t d_b (world); nullopt when the rays are
// near parallel, it lies behind either camera, or the rays pass farther apart than
// max_gap_rad seen from camera B (a mismatch: two views of one point meet, up to the poses'
// noise; 0 disables).
std::optional<Vector3d> triangulate_midpoint(const Isometry3d& X_WA, const Vector3d& d_a,
                                             const Isometry3d& X_WB, const Vector3d& d_b,
                                             double max_gap_rad) {
  const Vector3d w = X_WA.translation() - X_WB.translation();
  const double a = d_a.dot(d_a), b = d_a.dot(d_b), c = d_b.dot(d_b);
  const double d = d_a.dot(w), e = d_b.dot(w);
  const double den = a * c - b * b;
  if (den < 1e-12 * a * c) return std::nullopt;
  const double s = (b * e - c * d) / den, t = (a * e - b * d) / den;
  if (s <= 0 || t <= 0) return std::nullopt;
  const Vector3d p_a = X_WA.translation() + s * d_a, p_b = X_WB.translation() + t * d_b;
  if (max_gap_rad > 0 && (p_a - p_b).norm() > max_gap_rad * t * std::sqrt(c)) return std::nullopt;
  return 0.5 * (p_a + p_b);
}

// Which side of a border line the wall is on (-1: lower across-coordinates, +1: higher, 0:
// undecided): the one where the mask is clear 4 px off the line.
int wall_side(const cv::Mat& mask, bool vertical, double a, double b, double mean_along, int lo,
              int hi) {
  const int n_across = vertical ? mask.cols : mask.rows;
  auto mask_at = [&](int along, int across) {
    return vertical ? mask.at<uint8_t>(along, across) : mask.at<uint8_t>(across, along);
  };
  int clear_minus = 0, clear_plus = 0;
  for (int t = lo; t <= hi; ++t) {
    const int x = static_cast<int>(std::lround(a + b * (t - mean_along)));
    if (x - 4 >= 0) clear_minus += mask_at(t, x - 4) == 0;
    if (x + 4 < n_across) clear_plus += mask_at(t, x + 4) == 0;
  }
  return clear_minus == clear_plus ? 0 : clear_minus > clear_plus ? -1 : 1;
}

// The mask's border lies where the parallax first exceeds the threshold: on a frame's inner
// face (jamb, sill, lintel) next to the wall's edge it stays below it for a few pixels, so the
// cut sits that far inside the opening. The wall's edge itself is a straight step in the image
// (the face turns away from the light): along the line, the mean signed gradient across it
// peaks there, while the texture's gradients cancel. Searched on the wall's side of the cut
// (where the mask is clear), up to snap_px; sub-pixel by a parabola through the peak.
// Returns a unchanged when no step stands out. `smooth` is the grey image blurred; the gradient
// across the line is its 3x3 Sobel derivative (as cv::Sobel, border reflected), taken only at
// the pixels searched (issue 15: two whole-image Sobel passes for a few lines' pixels).
double snap_to_edge(const cv::Mat& smooth, const cv::Mat& mask, bool vertical, double a, double b,
                    double mean_along, int lo, int hi, const IngressParams& p) {
  const int n_across = vertical ? mask.cols : mask.rows;
  const int n_along = vertical ? mask.rows : mask.cols;
  auto reflect = [](int i, int n) {
    return i < 0 ? std::min(1, n - 1) : i >= n ? std::max(n - 2, 0) : i;
  };
  // d/d(across) at (along, across), 1 <= across <= n_across - 2.
  auto at = [&](int along, int across) -> float {
    const int m = reflect(along - 1, n_along), q = reflect(along + 1, n_along);
    auto px = [&](int al, int ac) -> int {
      return vertical ? smooth.at<uint8_t>(al, ac) : smooth.at<uint8_t>(ac, al);
    };
    const int d = (px(m, across + 1) - px(m, across - 1)) +
                  2 * (px(along, across + 1) - px(along, across - 1)) +
                  (px(q, across + 1) - px(q, across - 1));
    return static_cast<float>(d);
  };
  const int side = wall_side(mask, vertical, a, b, mean_along, lo, hi);
  if (side == 0) return a;
  const int k_wall = static_cast<int>(std::ceil(p.snap_px));
  std::vector<double> response;  // |mean gradient| at offsets k = -1 .. k_wall towards the wall
  // Whole-pixel offsets from the line rounded at its centre, so the parabola's fraction is one
  // of pixels, not of rounding. Each offset's sum runs along the line in order; the offsets
  // are the inner loop so a vertical line's pixels are read row by row (issue 15: reading a
  // column per offset missed the cache on every pixel).
  const double a0 = std::round(a);
  const int n_k = k_wall + 2;
  std::vector<double> sum(n_k, 0.0);
  std::vector<int> n(n_k, 0);
  for (int t = lo; t <= hi; ++t) {
    const int x0 = static_cast<int>(std::lround(a0 + b * (t - mean_along)));
    for (int j = 0; j < n_k; ++j) {
      const int x = x0 + side * (j - 1);
      if (x < 1 || x >= n_across - 1) continue;
      sum[j] += at(t, x), ++n[j];
    }
  }
  for (int j = 0; j < n_k; ++j) response.push_back(n[j] > 0 ? std::abs(sum[j] / n[j]) : 0.0);
  // The face's far edge (face to room) can be the stronger step: take the peak nearest the wall
  // among those at least 0.8 of the strongest (0.5 let wall-texture steps through on rendered
  // views: widths up to 61.3 cm; the strongest alone took far edges on the synthetic face).
  constexpr double kPeakShare = 0.8;
  const double strongest = *std::max_element(response.begin(), response.end());
  if (strongest < p.snap_min_gradient) return a;  // no edge
  int i = -1;
  for (int j = static_cast<int>(response.size()) - 2; j >= 1 && i < 0; --j)
    if (response[j] >= kPeakShare * strongest && response[j] >= response[j - 1] &&
        response[j] >= response[j + 1])
      i = j;
  if (i < 0) return a;  // the peak is not inside the window
  const double l = response[i - 1], c = response[i], r = response[i + 1];
  const double den = l - 2 * c + r;
  const double frac = den < 0 ? 0.5 * (l - r) / den : 0.0;
  return a0 + side * ((i - 1) + frac);
}

// The standard Hough transform (Duda & Hart, CACM 1972) of a list of points, on the
// conventions of cv::HoughLines with a 1 px rho step (rho = x cos(theta) + y sin(theta), theta
// from theta_lo in steps of theta_step, round((theta_hi - theta_lo) / theta_step) of them; the
// tables in float, the angle summed in float; a line is a bin with more than `threshold` votes,
// strictly above its neighbours before it in rho and in theta and at least those after; the most
// votes first, ties in theta then rho order), so the lines are cv::HoughLines' own, but the
// points are the border's list rather than a scan of the whole image for them (issue 15: three
// scans of the image's 300 000 pixels per frame). Appends (rho, theta, votes) to `out`.
void hough_lines(const std::vector<cv::Point>& px, cv::Size size, double theta_lo, double theta_hi,
                 double theta_step, int threshold, std::vector<cv::Vec3f>* out) {
  const int n_theta = cvRound((theta_hi - theta_lo) / theta_step);
  const int n_rho = 2 * (size.width + size.height) + 1;
  if (n_theta <= 0) return;
  const int stride = n_rho + 2;  // a zero bin before and after each row and angle
  std::vector<int> votes(static_cast<size_t>(n_theta + 2) * stride, 0);
  const int rho_offset = (n_rho - 1) / 2;
  float theta = static_cast<float>(theta_lo);
  for (int k = 0; k < n_theta; ++k, theta += static_cast<float>(theta_step)) {
    const float c = static_cast<float>(std::cos(static_cast<double>(theta)));
    const float s = static_cast<float>(std::sin(static_cast<double>(theta)));
    int* row = votes.data() + static_cast<size_t>(k + 1) * stride + 1 + rho_offset;
    for (const cv::Point& q : px)
      ++row[cvRound(static_cast<float>(q.x) * c + static_cast<float>(q.y) * s)];
  }
  std::vector<int> peaks;
  for (int k = 0; k < n_theta; ++k)
    for (int r = 0; r < n_rho; ++r) {
      const int i = (k + 1) * stride + r + 1, v = votes[i];
      if (v > threshold && v > votes[i - 1] && v >= votes[i + 1] && v > votes[i - stride] &&
          v >= votes[i + stride])
        peaks.push_back(i);
    }
  std::sort(peaks.begin(), peaks.end(),
            [&](int l, int r) { return votes[l] > votes[r] || (votes[l] == votes[r] && l < r); });
  for (const int i : peaks) {
    const int k = i / stride - 1, r = i - (k + 1) * stride - 1;
    out->emplace_back(
        static_cast<float>(r) - static_cast<float>(n_rho - 1) * 0.5f,
        static_cast<float>(theta_lo) + static_cast<float>(k) * static_cast<float>(theta_step),
        static_cast<float>(votes[i]));
  }
}

}  // namespace

// The wall's front edge beyond a frame's inner face (jamb, sill, lintel; issue 15, the thickness
// bias). A face of a wall t thick runs from the front edge, on the wall plane, straight back
// along the wall's normal, so given where its front edge lies in the image the face is a known
// plane: the one through that edge's line on the wall plane that holds the wall's normal. Its
// homography (paper eq. 2 with the face's n~) maps the reference onto the current image across
// the face as the wall's does beyond it; the front edge is where the two models together explain
// the views (a change point, as in Irani & Anandan's plane + parallax, ECCV 1996).
// Searched as far as a face can reach: a face's far edge at `across` from the principal point
// has its front edge `across` t / Z further out, and it shows only on the side away from the
// principal point (beyond, the front edge hides it). The first 2 sigma of the mask's blur are
// left out (the room's difference spread over the border). Returns a unchanged when no face
// shows.
double face_front_edge(int side, bool vertical, double a, double b, double mean_along, int lo,
                       int hi, const CutGeometry& g, const IngressParams& p) {
  if (!g.camera || g.image.empty() || g.reference.size() != g.image.size() ||
      !(g.wall_depth_m > 0) || !std::isfinite(g.wall_depth_m))
    return a;
  const double centre = vertical ? g.principal_px.x() : g.principal_px.y();
  if (side == 0 || (a - centre) * side <= 0) return a;
  const int n_across = vertical ? g.image.cols : g.image.rows;
  const double reach =
      std::min(std::abs(a - centre) * p.max_wall_thickness_m / g.wall_depth_m, 0.25 * n_across);
  const int k0 = static_cast<int>(std::ceil(2 * p.parallax_blur_sigma_px)) + 1;
  const int e_max = static_cast<int>(std::floor(reach));
  const int k_end = e_max + k0 + 8;  // beyond the farthest front edge: the wall's own level
  if (e_max <= k0) return a;
  const CameraModel& camera = *g.camera;
  const Matrix3d R_12 = g.wall.R_21.transpose();
  const Vector3d& t_12 = g.wall.t_12;
  const Vector3d n2 = g.wall.n_2();  // n2~: n2~^T X2 = 1 on the wall
  if (!n2.allFinite()) return a;
  const Vector3d c1_2 = -(g.wall.R_21 * t_12);  // camera 1's centre in camera 2
  auto pixel = [&](double along, double across) {
    return vertical ? Vector2d(across, along) : Vector2d(along, across);
  };
  // The reference's value where the plane n~ (camera 2, n~^T X = 1) puts the point seen along
  // ray r2, bilinear; nullopt off the reference or behind a camera.
  auto reference_at = [&](const Vector3d& n, const Vector3d& r2) -> std::optional<float> {
    const double den = n.dot(r2);
    if (!(den > 0)) return std::nullopt;
    const auto u1 = camera.project(R_12 * (r2 / den) + t_12);
    if (!u1 || !(u1->x() >= 0 && u1->y() >= 0 && u1->x() <= g.reference.cols - 2 &&
                 u1->y() <= g.reference.rows - 2))
      return std::nullopt;
    const int x = static_cast<int>(u1->x()), y = static_cast<int>(u1->y());
    const float fx = static_cast<float>(u1->x() - x), fy = static_cast<float>(u1->y() - y);
    const uint8_t* r0 = g.reference.ptr<uint8_t>(y) + x;
    const uint8_t* r1 = g.reference.ptr<uint8_t>(y + 1) + x;
    return (1 - fy) * ((1 - fx) * r0[0] + fx * r0[1]) + fy * ((1 - fx) * r1[0] + fx * r1[1]);
  };
  // The strip: whole rows (lines across the side) of k0 .. k_end px towards the wall, every
  // few along the side (the cost, not the answer, grows with them), kept only where the wall
  // model sees every pixel, so every candidate sums the same pixels.
  const int n_k = k_end - k0 + 1;
  constexpr int kMaxRows = 48;
  const int step = std::max(1, (hi - lo + 1 + kMaxRows - 1) / kMaxRows);
  const double a0 = std::round(a);
  std::vector<Vector3d> ray;  // row-major, n_k a row
  std::vector<float> current, wall_diff;
  for (int t = lo; t <= hi; t += step) {
    const int x0 = static_cast<int>(std::lround(a0 + b * (t - mean_along)));
    bool whole = true;
    const size_t begin = ray.size();
    for (int k = k0; k <= k_end && whole; ++k) {
      const int x = x0 + side * k;
      if (x < 0 || x >= n_across) {
        whole = false;
        break;
      }
      const Vector2d u = pixel(t, x);
      const Vector3d r = camera.ray(u);
      const auto ref = reference_at(n2, r);
      if (!ref) {
        whole = false;
        break;
      }
      const float cur = g.image.at<uint8_t>(static_cast<int>(u.y()), static_cast<int>(u.x()));
      ray.push_back(r), current.push_back(cur), wall_diff.push_back(std::abs(cur - *ref));
    }
    if (!whole) {
      ray.resize(begin), current.resize(begin), wall_diff.resize(begin);
    }
  }
  const int n_rows = static_cast<int>(ray.size()) / n_k;
  if (n_rows < 4) return a;
  // wall_from[j]: the wall model's difference summed over k >= k0 + j.
  std::vector<double> wall_from(n_k + 1, 0.0);
  for (int j = n_k - 1; j >= 0; --j) {
    wall_from[j] = wall_from[j + 1];
    for (int r = 0; r < n_rows; ++r) wall_from[j] += wall_diff[r * n_k + j];
  }
  // cost[e - k0]: the face's model over k0 <= k < e, the wall's beyond; e = k0: no face.
  constexpr double kNone = std::numeric_limits<double>::infinity();
  std::vector<double> cost(e_max - k0 + 1, kNone);
  cost[0] = wall_from[0];
  // Past the least the cost only rises (the face's model takes in more of the wall): the search
  // stops once a candidate two or more beyond the least has risen face_stop_rise a line above
  // it, and a candidate's sum stops there too (issue 15: the candidates' pixels grow with the
  // square of the reach; the search's vision CPU p99 was 11 ms against 7 ms without it).
  double least_so_far = cost[0];
  int best_so_far = 0;
  const double stop = p.face_stop_rise * n_rows;
  bool risen = false;  // stopped: the cost rose face_stop_rise above its least
  const double along_lo = lo, along_hi = hi;
  for (int e = k0 + 1; e <= e_max; ++e) {
    // The front edge's line on the wall plane, and the face plane through it along the wall's
    // normal.
    auto on_wall = [&](double along) -> std::optional<Vector3d> {
      const Vector3d r =
          camera.ray(pixel(along, a0 + b * (along - mean_along) + side * static_cast<double>(e)));
      const double den = n2.dot(r);
      if (!(den > 0)) return std::nullopt;
      return Vector3d(r / den);
    };
    const auto X_lo = on_wall(along_lo), X_hi = on_wall(along_hi);
    if (!X_lo || !X_hi) continue;
    const Vector3d m = n2.normalized().cross(*X_hi - *X_lo);
    const double offset = m.dot(*X_lo);
    if (!(std::abs(offset) > 1e-9 * m.norm() * X_lo->norm())) continue;  // seen edge-on
    const Vector3d face = m / offset;                                    // n~ of the face
    if (!(face.dot(c1_2) < 1)) continue;  // camera 1 on the face's far side: hidden from it
    double sum = wall_from[e - k0];
    bool ok = true;
    const bool may_stop = p.face_stop_rise > 0 && e - k0 >= best_so_far + 2;
    bool stopped = false;
    for (int r = 0; r < n_rows && ok && !stopped; ++r) {
      for (int j = 0; j < e - k0; ++j) {
        const auto ref = reference_at(face, ray[r * n_k + j]);
        if (!ref) {
          ok = false;
          break;
        }
        sum += std::abs(current[r * n_k + j] - *ref);
      }
      stopped = may_stop && sum - least_so_far >= stop;
    }
    if (stopped) {
      risen = true;
      break;
    }
    if (!ok) continue;
    cost[e - k0] = sum;
    if (sum < least_so_far) least_so_far = sum, best_so_far = e - k0;
  }
  // The front edge is the least cost's candidate, to a fraction of a pixel by the parabola
  // through it and its neighbours (the cost falls as the face's model takes in more of the face
  // and rises once it takes in the wall beyond its front edge). Not the farthest candidate near
  // the least: where the face's texture is faint the cost is flat over pixels either side of
  // the front edge, and the farthest of them put the flown widths 1-3 cm wide (issue 15,
  // ingress_photo seeds 9802-9805, 9 cm walls). A strip whose cost never rises by
  // face_min_rise tells the face from the wall nowhere (a smooth wall).
  double least = kNone, most = 0;
  int best = -1;
  for (int i = 0; i < static_cast<int>(cost.size()); ++i)
    if (std::isfinite(cost[i])) {
      if (cost[i] < least) least = cost[i], best = i;
      most = std::max(most, cost[i]);
    }
  if (best <= 0 || (!risen && (most - least) / n_rows < p.face_min_rise)) return a;
  double frac = 0;
  if (best + 1 < static_cast<int>(cost.size()) && std::isfinite(cost[best + 1]) &&
      std::isfinite(cost[best - 1])) {
    const double curvature = cost[best - 1] - 2 * cost[best] + cost[best + 1];
    if (curvature > 0)
      frac = std::clamp(0.5 * (cost[best - 1] - cost[best + 1]) / curvature, -0.5, 0.5);
  }
  return a0 + side * (best + k0 + frac);
}

cv::Mat parallax_image(const cv::Mat& gray, const IngressParams& p) {
  assert(gray.type() == CV_8UC1);
  // The mask can be made on a grid parallax_decimation times coarser and scaled back up (issue
  // 15: the warp, blurs and morphology at full size were a fifth of the vision's time on a
  // photographed wall). Its border moves by up to half a coarse pixel; mask_cuts fits lines to
  // it and snaps them to the wall's edge in the full-size image.
  const int d = p.parallax_decimation;
  cv::Mat small;
  if (d > 1)
    cv::resize(gray, small, cv::Size((gray.cols + d - 1) / d, (gray.rows + d - 1) / d), 0, 0,
               cv::INTER_AREA);
  else
    small = gray;
  cv::Mat out;
  if (p.parallax_blur_sigma_px > 0)
    cv::GaussianBlur(small, out, cv::Size(), p.parallax_blur_sigma_px / d);
  else
    out = small.clone();  // never the caller's pixels
  return out;
}

cv::Mat off_wall_mask(const cv::Mat& image, const cv::Mat& reference, const Matrix3d& H_21,
                      const CameraModel& camera, const std::vector<Vector2d>& wall_px,
                      const IngressParams& p) {
  assert(image.size() == reference.size());
  return off_wall_mask_of_parallax_images(parallax_image(image, p), parallax_image(reference, p),
                                          image.size(), H_21, camera, wall_px, p);
}

cv::Mat off_wall_mask_of_parallax_images(const cv::Mat& a, const cv::Mat& b, cv::Size size,
                                         const Matrix3d& H_21, const CameraModel& camera,
                                         const std::vector<Vector2d>& wall_px,
                                         const IngressParams& p, cv::Mat* diff_out) {
  assert(a.type() == CV_8UC1 && b.type() == CV_8UC1);
  const int d = p.parallax_decimation;
  const cv::Size small_size((size.width + d - 1) / d, (size.height + d - 1) / d);
  assert(a.size() == small_size && b.size() == small_size);
  // Pixel centres: full u = sx (u_small + 0.5) - 0.5.
  const double sx = static_cast<double>(size.width) / small_size.width;
  const double sy = static_cast<double>(size.height) / small_size.height;
  // Where each current pixel's wall point lies in the reference image, and how much the two
  // images differ there; a pixel the reference did not see differs by 0: no evidence, counts as
  // wall.
  cv::Mat diff;
  if (!camera.has_distortion()) {
    Matrix3d S = Matrix3d::Identity(), S_inv = Matrix3d::Identity();  // full -> small, back
    S(0, 0) = 1 / sx, S(1, 1) = 1 / sy, S(0, 2) = 0.5 / sx - 0.5, S(1, 2) = 0.5 / sy - 0.5;
    S_inv(0, 0) = sx, S_inv(1, 1) = sy, S_inv(0, 2) = 0.5 * sx - 0.5, S_inv(1, 2) = 0.5 * sy - 0.5;
    const Matrix3d H_small = S * H_21 * S_inv;
    diff = warp_abs_diff(a, b, H_small.inverse());
  } else {
    cv::Mat warped, seen;
    const cv::Mat seen_ref(small_size, CV_8UC1, cv::Scalar(255));
    // Raw current pixel -> undistorted -> H^-1 -> raw reference pixel, exactly on a grid every
    // kStep (coarse) pixels and bilinearly between (the map is smooth; undistorting every pixel
    // by iteration would cost ~100 ms a frame).
    const int kStep = std::max(2, 8 / d);
    const Matrix3d K = camera.K(), K_inv = K.inverse(), H_12 = H_21.inverse();
    const int cols = small_size.width, rows = small_size.height;
    const int gw = (cols - 1 + kStep - 1) / kStep + 1;
    const int gh = (rows - 1 + kStep - 1) / kStep + 1;
    std::vector<cv::Point2f> grid(gw * gh);
    for (int j = 0; j < gh; ++j)
      for (int i = 0; i < gw; ++i) {
        const double us = std::min(i * kStep, cols - 1), vs = std::min(j * kStep, rows - 1);
        const Vector2d u2(sx * (us + 0.5) - 0.5, sy * (vs + 0.5) - 0.5);
        const Vector3d r1 = K_inv * (H_12 * (K * camera.ray(u2)));
        const auto u1 = r1.z() > 0 ? camera.project(r1) : std::nullopt;
        grid[j * gw + i] = u1 ? cv::Point2f((u1->x() + 0.5) / sx - 0.5, (u1->y() + 0.5) / sy - 0.5)
                              : cv::Point2f(-1e6f, -1e6f);
      }
    cv::Mat map_x(small_size, CV_32FC1), map_y(small_size, CV_32FC1);
    for (int v = 0; v < rows; ++v) {
      const int j = std::min(v / kStep, gh - 2);
      const float y0 = j * kStep, y1 = std::min((j + 1) * kStep, rows - 1);
      const float fy = (v - y0) / (y1 - y0);
      for (int u = 0; u < cols; ++u) {
        const int i = std::min(u / kStep, gw - 2);
        const float x0 = i * kStep, x1 = std::min((i + 1) * kStep, cols - 1);
        const float fx = (u - x0) / (x1 - x0);
        const cv::Point2f q =
            (1 - fy) * ((1 - fx) * grid[j * gw + i] + fx * grid[j * gw + i + 1]) +
            fy * ((1 - fx) * grid[(j + 1) * gw + i] + fx * grid[(j + 1) * gw + i + 1]);
        map_x.at<float>(v, u) = q.x;
        map_y.at<float>(v, u) = q.y;
      }
    }
    cv::remap(b, warped, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    cv::remap(seen_ref, seen, map_x, map_y, cv::INTER_NEAREST, cv::BORDER_CONSTANT);
    cv::absdiff(a, warped, diff);
    diff.setTo(0, seen == 0);
  }
  // The threshold follows the difference on the wall itself (noise, lighting, a slightly off
  // homography), measured at the wall's inlier features.
  std::vector<uint8_t> on_wall;
  for (const auto& px : wall_px) {
    if (!px.allFinite()) continue;
    const double us = (px.x() + 0.5) / sx - 0.5, vs = (px.y() + 0.5) / sy - 0.5;
    if (!(std::abs(us) < 1e6 && std::abs(vs) < 1e6)) continue;
    const int u = static_cast<int>(std::lround(us)), v = static_cast<int>(std::lround(vs));
    if (u >= 0 && v >= 0 && u < diff.cols && v < diff.rows)
      on_wall.push_back(diff.at<uint8_t>(v, u));
  }
  double threshold = p.parallax_min_diff;
  if (!on_wall.empty()) {
    std::nth_element(on_wall.begin(), on_wall.begin() + on_wall.size() / 2, on_wall.end());
    threshold = std::max(threshold, p.parallax_noise_k * on_wall[on_wall.size() / 2]);
  }
  if (diff_out) *diff_out = diff;
  cv::Mat mask;
  cv::threshold(diff, mask, threshold, 255, cv::THRESH_BINARY);
  // Closing fills the holes where the view beyond the wall has little texture (two samples of
  // it agree by chance); opening removes specks on the wall. Both keep a rectangle's border.
  // On the coarse grid, the odd size nearest below size / d.
  auto coarse = [d](int size_px) { return d == 1 ? size_px : 2 * (size_px / (2 * d)) + 1; };
  if (p.parallax_close_px > 1 && coarse(p.parallax_close_px) > 1) {
    const int k = coarse(p.parallax_close_px);
    cv::morphologyEx(mask, mask, cv::MORPH_CLOSE,
                     cv::getStructuringElement(cv::MORPH_RECT, {k, k}));
  }
  if (p.parallax_open_px > 1 && coarse(p.parallax_open_px) > 1) {
    const int k = coarse(p.parallax_open_px);
    cv::morphologyEx(mask, mask, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_RECT, {k, k}));
  }
  if (d == 1) return mask;
  // Bilinear up and halfway: the border lies between the coarse pixels' centres.
  cv::Mat full;
  cv::resize(mask, full, size, 0, 0, cv::INTER_LINEAR);
  cv::threshold(full, full, 127, 255, cv::THRESH_BINARY);
  return full;
}

void line_cuts(const cv::Mat& image, const IngressParams& p, std::vector<double>* x_cuts,
               std::vector<double>* y_cuts, std::vector<cv::Vec4i>* kept) {
  // Smoothing first: the wall's own texture gives short edges everywhere, the opening's border
  // one long straight edge that survives the blur while the texture's break up.
  cv::Mat smooth, edges;
  if (p.blur_sigma_px > 0)
    cv::GaussianBlur(image, smooth, cv::Size(), p.blur_sigma_px);
  else
    smooth = image;
  cv::Canny(smooth, edges, p.canny_low, p.canny_high);
  std::vector<cv::Vec4i> segments;
  cv::HoughLinesP(edges, segments, 1.0, CV_PI / 180.0, p.hough_threshold,
                  p.hough_min_length_frac * image.cols, p.hough_max_gap_px);
  const double tilt = std::tan(p.max_line_tilt_deg * M_PI / 180.0);
  std::vector<double> xs{0.0, static_cast<double>(image.cols)};
  std::vector<double> ys{0.0, static_cast<double>(image.rows)};
  for (const auto& s : segments) {
    const double dx = std::abs(s[2] - s[0]), dy = std::abs(s[3] - s[1]);
    if (dx <= tilt * dy) {
      xs.push_back(0.5 * (s[0] + s[2]));
    } else if (dy <= tilt * dx) {
      ys.push_back(0.5 * (s[1] + s[3]));
    } else {
      continue;
    }
    if (kept) kept->push_back(s);
  }
  *x_cuts = merged(xs, p.merge_px);
  *y_cuts = merged(ys, p.merge_px);
  // The image borders stay the outermost cuts even when a line lies near them.
  x_cuts->front() = 0.0, x_cuts->back() = image.cols;
  y_cuts->front() = 0.0, y_cuts->back() = image.rows;
}

// Border pixels in cv::findNonZero's order (row by row, x increasing) and where each row's run
// starts, so the pixels near a line are looked for only in the x-range of each row that can
// hold them instead of among all of them for every line (issue 15: on a photographed wall the
// border has thousands of pixels and the Hough transform dozens of lines, and testing every
// pixel against every line took 40 % of the vision's time at 60 fps).
struct BorderPixels {
  std::vector<cv::Point> px;
  std::vector<size_t> row_start;  // row y's pixels are px[row_start[y], row_start[y + 1])

  BorderPixels(std::vector<cv::Point> pixels, int rows)
      : px(std::move(pixels)), row_start(rows + 1) {
    size_t k = 0;
    for (int y = 0; y <= rows; ++y) {
      while (k < px.size() && px[k].y < y) ++k;
      row_start[y] = k;
    }
  }

  // Appends to `out`, in px's order, every pixel q with keep(q), where keep(q) implies
  // |cx q.x + cy q.y + c0| <= w: rows are searched only where that can hold (with a margin of
  // two pixels for rounding), and keep() itself decides, so the selection is exactly that of
  // testing keep() on every pixel, in the same order.
  template <class Keep>
  void select(double cx, double cy, double c0, double w, int cols, const Keep& keep,
              std::vector<const cv::Point*>* out) const {
    for (size_t y = 0; y + 1 < row_start.size(); ++y) {
      const size_t b = row_start[y], e = row_start[y + 1];
      if (b == e) continue;
      const double t = cy * static_cast<double>(y) + c0;
      double x_lo = -1.0, x_hi = cols + 1.0;
      if (std::abs(cx) > 1e-9) {
        const double x1 = (-w - t) / cx, x2 = (w - t) / cx;
        x_lo = std::max(x_lo, std::min(x1, x2) - 2.0);
        x_hi = std::min(x_hi, std::max(x1, x2) + 2.0);
        if (!(x_lo <= x_hi)) continue;
      } else if (std::abs(t) > w + std::abs(cx) * (cols + 1.0) + 1e-6) {
        continue;
      }
      const int lo = static_cast<int>(std::floor(x_lo)), hi = static_cast<int>(std::ceil(x_hi));
      auto it = std::lower_bound(px.begin() + b, px.begin() + e, lo,
                                 [](const cv::Point& q, int x) { return q.x < x; });
      for (; it != px.begin() + e && it->x <= hi; ++it)
        if (keep(*it)) out->push_back(&*it);
    }
  }
};

void mask_cuts(const cv::Mat& mask, const IngressParams& p, std::vector<double>* x_cuts,
               std::vector<double>* y_cuts, std::vector<cv::Vec4i>* kept, const cv::Mat& image) {
  assert(mask.type() == CV_8UC1);
  assert(image.empty() || (image.type() == CV_8UC1 && image.size() == mask.size()));
  cv::Mat smooth;
  if (!image.empty() && p.snap_px > 0) cv::GaussianBlur(image, smooth, cv::Size(), 1.0);
  // The mask's border, two pixels wide and straddling it, so the mean of a border line's
  // pixels is the border itself.
  const BorderPixels border_px(mask_border_pixels(mask), mask.rows);
  const std::vector<cv::Point>& px = border_px.px;
  // The standard Hough transform (full lines, votes from anywhere along them) rather than the
  // probabilistic one: the border is ragged by a few pixels where the view beyond the wall
  // agrees with it by chance, which breaks a segment walk but barely spreads the votes.
  // Only the angles a cut can have are voted on (near 0, pi and pi/2: a tenth of the 180 the
  // full transform accumulates; issue 15), strongest line first.
  const double tilt = p.max_line_tilt_deg * M_PI / 180.0;
  constexpr double kThetaStep = CV_PI / 180.0;
  std::vector<cv::Vec3f> lines;  // rho, theta, votes
  if (!px.empty()) {
    for (const auto& [lo, hi] : {std::pair{0.0, tilt + kThetaStep}, std::pair{CV_PI - tilt, CV_PI},
                                 std::pair{CV_PI / 2 - tilt, CV_PI / 2 + tilt + kThetaStep}})
      hough_lines(px, mask.size(), lo, hi, kThetaStep, p.hough_threshold, &lines);
    std::stable_sort(lines.begin(), lines.end(),
                     [](const cv::Vec3f& l, const cv::Vec3f& r) { return l[2] > r[2]; });
  }
  const double min_length = p.hough_min_length_frac * mask.cols;
  std::vector<double> xs{0.0, static_cast<double>(mask.cols)};
  std::vector<double> ys{0.0, static_cast<double>(mask.rows)};
  // The lines already refined, as across = a + b (along - mean_along) over [lo, hi]. One border
  // side gets dozens of Hough lines (neighbouring rho and theta bins of a two-pixel-wide,
  // ragged border); one that stays within kSamePx of a refined line where that line has border
  // pixels would select the same pixels and give the same cut, so it is not refined again
  // (issue 15: refining them all was a quarter of the vision's time on a photographed wall).
  struct Fitted {
    bool vertical;
    double a, b, mean_along;
    int lo, hi;
  };
  std::vector<Fitted> fitted;
  constexpr double kSamePx = 2.0;
  for (const auto& l : lines) {
    const double rho = l[0], theta = l[1];
    const bool vertical = std::min(theta, CV_PI - theta) <= tilt;
    if (!vertical && std::abs(theta - CV_PI / 2) > tilt) continue;
    {
      // The Hough line's across-coordinate at `along`: x at row y for a vertical line.
      const double c = std::cos(theta), s = std::sin(theta);
      auto hough_across = [&](double t) {
        return vertical ? (rho - t * s) / c : (rho - t * c) / s;
      };
      const bool seen = std::any_of(fitted.begin(), fitted.end(), [&](const Fitted& f) {
        if (f.vertical != vertical) return false;
        for (const int t : {f.lo, f.hi})
          if (std::abs(hough_across(t) - (f.a + f.b * (t - f.mean_along))) > kSamePx) return false;
        return true;
      });
      if (seen) continue;
    }
    // The strongest distinct lines only: a mask left ragged all over (the view off the wall
    // with little texture, a poor homography) gives hundreds, and refining every one made the
    // slowest frames 3x the median (issue 15); an opening's sides are among the strongest.
    if (static_cast<int>(fitted.size()) >= p.max_border_lines) break;
    // Refine on the border pixels near the line: fit the across-coordinate a + b * along by
    // least squares twice, narrowing the band; the cut is its mean (the fit at the centre).
    auto along = [&](const cv::Point& q) { return vertical ? q.y : q.x; };
    auto across = [&](const cv::Point& q) { return vertical ? q.x : q.y; };
    const double c = std::cos(theta), s = std::sin(theta);
    double a = 0, b = 0, mean_along = 0;
    std::vector<const cv::Point*> band;
    border_px.select(
        c, s, -rho, 3.0, mask.cols,
        [&](const cv::Point& q) { return std::abs(q.x * c + q.y * s - rho) <= 3.0; }, &band);
    for (int pass = 0; pass < 2 && band.size() >= 2; ++pass) {
      double sa = 0, sx = 0;
      for (const auto* q : band) sa += along(*q), sx += across(*q);
      mean_along = sa / band.size(), a = sx / band.size();
      double sab = 0, saa = 0;
      for (const auto* q : band) {
        sab += (along(*q) - mean_along) * (across(*q) - a);
        saa += (along(*q) - mean_along) * (along(*q) - mean_along);
      }
      b = saa > 0 ? sab / saa : 0.0;
      std::vector<const cv::Point*> next;
      const auto near_fit = [&](const cv::Point& q) {
        return std::abs(across(q) - (a + b * (along(q) - mean_along))) <= 2.0;
      };
      // |across - b along + (b mean_along - a)| <= 2, across = x for a vertical line.
      if (vertical)
        border_px.select(1.0, -b, b * mean_along - a, 2.0, mask.cols, near_fit, &next);
      else
        border_px.select(-b, 1.0, b * mean_along - a, 2.0, mask.cols, near_fit, &next);
      band.swap(next);
    }
    if (band.empty()) continue;
    // Length: the along-coordinates the band covers (a full line may hold short pieces).
    std::vector<uint8_t> covered(vertical ? mask.rows : mask.cols, 0);
    int lo = static_cast<int>(covered.size()), hi = -1;
    for (const auto* q : band) {
      covered[along(*q)] = 1;
      lo = std::min(lo, along(*q)), hi = std::max(hi, along(*q));
    }
    fitted.push_back({vertical, a, b, mean_along, lo, hi});
    if (std::count(covered.begin(), covered.end(), 1) < min_length) continue;
    if (!smooth.empty()) a = snap_to_edge(smooth, mask, vertical, a, b, mean_along, lo, hi, p);
    (vertical ? xs : ys).push_back(a);
    if (kept) {
      const double e0 = a + b * (lo - mean_along), e1 = a + b * (hi - mean_along);
      kept->push_back(vertical ? cv::Vec4i(cvRound(e0), lo, cvRound(e1), hi)
                               : cv::Vec4i(lo, cvRound(e0), hi, cvRound(e1)));
    }
  }
  *x_cuts = merged(xs, p.merge_px);
  *y_cuts = merged(ys, p.merge_px);
  x_cuts->front() = 0.0, x_cuts->back() = mask.cols;
  y_cuts->front() = 0.0, y_cuts->back() = mask.rows;
}

TargetOutcome find_ingress_target(const Correspondences& c, const cv::Mat& image,
                                  const cv::Mat& reference, const PipelineParams& params) {
  const bool mask = params.ingress.parallax_mask && !reference.empty();
  return find_ingress_target(c, image, mask ? parallax_image(image, params.ingress) : cv::Mat(),
                             mask ? parallax_image(reference, params.ingress) : cv::Mat(), params);
}

TargetOutcome find_ingress_target(const Correspondences& c, const cv::Mat& image,
                                  const cv::Mat& image_parallax, const cv::Mat& reference_parallax,
                                  const PipelineParams& params) {
  assert(c.camera && c.mount);
  const IngressParams& p = params.ingress;
  TargetOutcome out;
  out.labels.assign(c.size(), Label::kOutlier);
  const auto planes = fit_two_homographies(c.x1, c.x2, params.homography);
  if (!planes) {
    out.reason = planes.reason();
    return out;
  }
  // The wall plane; motion capture's rotation picks the physical decomposition.
  const MocapMotion mocap = mocap_motion(c.pose_1, c.pose_2, *c.mount);
  if (mocap.baseline_m < params.waypoint.min_baseline_m) {
    out.reason = Reason::kSmallBaseline;
    return out;
  }
  const Isometry3d X_WC1 = camera_in_world(c.pose_1.X_WB(), c.mount->X_BC());
  const Isometry3d X_WC2 = camera_in_world(c.pose_2.X_WB(), c.mount->X_BC());
  // The wall is the nearer of the dominant plane and the one among its outliers (issue 15: where
  // the wall's photograph is dark and flat and the room's bright, the room's back wall seen
  // through the opening holds more matches than the wall around it; its homography made the
  // opening the only part of the view that agreed with the reference, and the behind check then
  // threw away nearly every frame). Nearer: the median depth of its triangulated inliers. Only a
  // plane whose decomposition agrees with motion capture's motion (as compute_waypoint checks)
  // counts: the second search also finds a dozen stray matches that fit some homography.
  const Matrix3d K = c.camera->K(), K_inv = K.inverse();
  const Isometry3d X_C2W = X_WC2.inverse();
  // Every match triangulated once with motion capture's poses (the planes' depths, the behind
  // and partial-view checks).
  const double max_gap_rad = p.max_ray_gap_px / K(0, 0);
  std::vector<std::optional<Vector3d>> X_W_match(c.size());
  for (size_t k = 0; k < c.size(); ++k)
    X_W_match[k] = triangulate_midpoint(X_WC1, X_WC1.linear() * c.camera->ray(c.u1[k]), X_WC2,
                                        X_WC2.linear() * c.camera->ray(c.u2[k]), max_gap_rad);
  struct Candidate {
    const HomographyFit* fit;
    Result<PlaneMotion> plane;
    double depth_m;
  };
  auto candidate = [&](const HomographyFit& f) {
    std::vector<Vector3d> r1, r2;
    std::vector<double> z;
    for (size_t k = 0; k < c.size(); ++k) {
      if (!f.inlier[k]) continue;
      r1.push_back(K_inv * c.x1[k].homogeneous());
      r2.push_back(K_inv * c.x2[k].homogeneous());
      if (X_W_match[k]) z.push_back((X_C2W * *X_W_match[k]).z());
    }
    DecompositionPrior prior;
    prior.R_21 = mocap.R_21;
    auto plane = decompose(calibrate_homography(f.H, K), r1, r2, prior, params.decomposition);
    if (plane) {
      constexpr double kDeg = M_PI / 180.0;
      if (direction_angle(plane->t_12, mocap.t_12) >
              params.waypoint.max_translation_angle_deg * kDeg ||
          rotation_angle(plane->R_21, mocap.R_21) > params.waypoint.max_rotation_error_deg * kDeg)
        plane = Result<PlaneMotion>::fail(Reason::kDecompositionFailed);
    }
    double depth = std::numeric_limits<double>::infinity();
    if (!z.empty()) {
      std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
      depth = z[z.size() / 2];
    }
    return Candidate{&f, std::move(plane), depth};
  };
  Candidate wall = candidate(planes->first);
  if (p.nearer_plane && planes->second) {
    Candidate other = candidate(*planes->second);
    // Nearer by a margin: on a solid wall the second search can find the wall again, a worse
    // fit of the same plane at the same depth, whose off-wall mask then shows false openings
    // (issue 15, ingress_solid_photo seed 3015).
    if (other.plane && (!wall.plane || other.depth_m < wall.depth_m - p.nearer_plane_margin_m))
      wall = std::move(other);
  }
  for (size_t i = 0; i < c.size(); ++i)
    if (wall.fit->inlier[i]) out.labels[i] = Label::kDominant;
  out.estimate.n_inliers_dominant = wall.fit->n_inliers;
  if (!wall.plane) {
    out.reason = wall.plane.reason();
    return out;
  }
  const PlaneMotion& plane = *wall.plane;
  const HomographyFit* const fit = wall.fit;

  // 2D histogram of wall inliers and off-wall features over the cells of the line cuts.
  std::vector<double> xc, yc;
  cv::Mat mask;
  CutGeometry geometry;
  if (p.parallax_mask && !reference_parallax.empty()) {
    std::vector<Vector2d> wall_px;
    for (size_t k = 0; k < c.size(); ++k)
      if (fit->inlier[k]) wall_px.push_back(c.u2[k]);
    mask = off_wall_mask_of_parallax_images(image_parallax, reference_parallax, image.size(),
                                            fit->H, *c.camera, wall_px, p);
    if (image_parallax.size() == image.size())  // the faces are searched at full size only
      geometry =
          CutGeometry{Vector2d(K(0, 2), K(1, 2)), wall.depth_m, plane, c.camera, image_parallax,
                      reference_parallax};
    mask_cuts(mask, p, &xc, &yc, &out.lines, image);
  } else {
    line_cuts(image, p, &xc, &yc, &out.lines);
  }
  const int nx = static_cast<int>(xc.size()) - 1, ny = static_cast<int>(yc.size()) - 1;
  // Prefix sums (ny+1) x (nx+1) of both counts, so each block costs O(1).
  std::vector<int> in((nx + 1) * (ny + 1), 0), off((nx + 1) * (ny + 1), 0);
  auto at = [&](std::vector<int>& v, int i, int j) -> int& { return v[j * (nx + 1) + i]; };
  // A wall inlier within cut_margin_px of a cut is no evidence against the cell it falls in: its
  // detector support straddles the border, and on the frame's inner face next to the wall's
  // edge the parallax is still within the homography's threshold.
  auto near_cut = [&](const std::vector<double>& cuts, double x) {
    const auto it = std::lower_bound(cuts.begin(), cuts.end(), x);
    return (it != cuts.end() && *it - x < p.cut_margin_px) ||
           (it != cuts.begin() && x - *(it - 1) < p.cut_margin_px);
  };
  // An outlier of the wall's homography where the dense comparison finds the wall (the mask
  // clear at its pixel) is not seen through an opening: a wall feature the homography's fit
  // missed, or a mismatch (issue 15, ingress_photo seed 9805: a second-plane fit over a dark
  // wall's few features left some of them off it beside and above the opening, and they
  // carried the block to the image border).
  auto off_wall = [&](size_t k) {
    if (fit->inlier[k]) return false;
    if (mask.empty() || !p.off_features_on_mask) return true;
    const int u = cvRound(c.u2[k].x()), v = cvRound(c.u2[k].y());
    return u < 0 || v < 0 || u >= mask.cols || v >= mask.rows || mask.at<uint8_t>(v, u) != 0;
  };
  for (size_t k = 0; k < c.size(); ++k) {
    const int i = cell_of(xc, c.u2[k].x()), j = cell_of(yc, c.u2[k].y());
    if (off_wall(k))
      ++at(off, i + 1, j + 1);
    else if (fit->inlier[k] && !near_cut(xc, c.u2[k].x()) && !near_cut(yc, c.u2[k].y()))
      ++at(in, i + 1, j + 1);
  }
  for (int j = 1; j <= ny; ++j)
    for (int i = 1; i <= nx; ++i) {
      at(in, i, j) += at(in, i - 1, j) + at(in, i, j - 1) - at(in, i - 1, j - 1);
      at(off, i, j) += at(off, i - 1, j) + at(off, i, j - 1) - at(off, i - 1, j - 1);
    }
  auto block = [&](std::vector<int>& v, int i0, int j0, int i1, int j1) {  // cells [i0,i1)x[j0,j1)
    return at(v, i1, j1) - at(v, i0, j1) - at(v, i1, j0) + at(v, i0, j0);
  };
  // A block whose outermost row or column of cells holds no off-wall features and is mostly
  // clear in the off-wall mask is not bounded by the opening: the same block without that row
  // holds the same features (issue 15, ingress_photo seed 9805: on a dark, flat wall
  // photograph the wall beside the opening holds no features at all, and the tie rule below
  // carried the block across it to the image border, a partial view of a whole opening).
  // Inside the block such cells stay: a smooth room's mask covers only part of the cells
  // between the ones holding its few features (seed 9401).
  std::vector<int> clear((nx + 1) * (ny + 1), 0);
  if (!mask.empty() && p.min_cell_mask_share > 0) {
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const cv::Rect cell = cv::Rect(cv::Point(cvRound(xc[i]), cvRound(yc[j])),
                                       cv::Point(cvRound(xc[i + 1]), cvRound(yc[j + 1]))) &
                              cv::Rect(0, 0, mask.cols, mask.rows);
        if (cell.area() > 0 && block(off, i, j, i + 1, j + 1) == 0)
          at(clear, i + 1, j + 1) =
              cv::countNonZero(mask(cell)) < p.min_cell_mask_share * cell.area();
      }
    for (int j = 1; j <= ny; ++j)
      for (int i = 1; i <= nx; ++i)
        at(clear, i, j) += at(clear, i - 1, j) + at(clear, i, j - 1) - at(clear, i - 1, j - 1);
  }
  auto clear_strip = [&](int i0, int j0, int i1, int j1) {
    return block(clear, i0, j0, i1, j1) == (i1 - i0) * (j1 - j0);
  };
  // Unless the cut beyond the strip is the opening's edge (issue 15, ingress_photo seed 9604: the
  // room seen through part of the opening flat grey, a strip with no features and 7-15 % mask
  // between the jamb's cut and the room's first features, and the block stopped 80-100 px
  // inside the jamb). The opening's edge is a border of the mask: along it the mask is set on
  // the block's side (what is seen past the edge moves against the wall) and clear 4 px out on
  // the wall's side, and the wall's inliers lie in the cell beyond. A line on a flat wall beside
  // the opening has no mask on either side (the strip is wall), and the image border has no
  // wall beyond (seed 9805).
  // edge_run[v][s][i][t]: how many lines t' < t across cut i (v 0: x cuts, lines are rows; 1: y
  // cuts) show that pattern for a block on side s (0: towards higher coordinates, 1: lower);
  // made when a clear strip first asks.
  const bool edge_test = !mask.empty() && p.min_cell_mask_share > 0 && p.edge_band_min_share > 0;
  const int edge_reach = static_cast<int>(std::ceil(p.snap_px)) + 4;  // the snap moved it out
  std::vector<std::vector<int>> edge_run[2][2];
  for (auto& v : edge_run)
    for (auto& s : v) s.resize(std::max(nx, ny) + 1);
  auto edge_lines = [&](bool vertical, int i, int s) -> const std::vector<int>& {
    std::vector<int>& run = edge_run[vertical ? 0 : 1][s][i];
    if (!run.empty()) return run;
    const int n_along = vertical ? mask.rows : mask.cols;
    const int n_across = vertical ? mask.cols : mask.rows;
    auto set = [&](int t, int x) {
      return x >= 0 && x < n_across &&
             (vertical ? mask.at<uint8_t>(t, x) : mask.at<uint8_t>(x, t)) != 0;
    };
    const int dir = s == 0 ? 1 : -1;  // towards the block
    const int a = static_cast<int>(std::lround(vertical ? xc[i] : yc[i]));
    const int x_wall = a - 4 * dir;
    run.assign(n_along + 1, 0);
    for (int t = 0; t < n_along; ++t) {
      bool edge = x_wall >= 0 && x_wall < n_across && !set(t, x_wall);
      if (edge) {
        bool band = false;
        for (int k = 0; k <= edge_reach && !band; ++k) band = set(t, a + k * dir);
        edge = band;
      }
      run[t + 1] = run[t] + edge;
    }
    return run;
  };
  // Cut i (of the x cuts when vertical) is the opening's edge for a block on side s spanning
  // cells [c0, c1) along it.
  auto opening_edge = [&](bool vertical, int i, int s, int c0, int c1) {
    if (!edge_test || i <= 0 || i >= (vertical ? nx : ny)) return false;
    // The wall's inliers in the cell beyond, over the block's span.
    const int beyond = s == 0 ? i - 1 : i;
    const int n_beyond =
        vertical ? block(in, beyond, c0, beyond + 1, c1) : block(in, c0, beyond, c1, beyond + 1);
    if (n_beyond < std::max(1, p.partial_frame_inliers)) return false;
    // The middle of the span: its ends hold the neighbouring sides.
    const std::vector<double>& along = vertical ? yc : xc;
    const double len = along[c1] - along[c0];
    const std::vector<int>& run = edge_lines(vertical, i, s);
    const int lo = std::max(0, static_cast<int>(std::ceil(along[c0] + 0.1 * len)));
    const int hi = std::min(static_cast<int>(run.size()) - 1,
                            static_cast<int>(std::floor(along[c1] - 0.1 * len)));
    return hi > lo && run[hi] - run[lo] >= p.edge_band_min_share * (hi - lo);
  };
  // The block's outermost column or row that is clear and not bounded by the opening's edge.
  auto wall_strip = [&](int i0, int j0, int i1, int j1) {
    return (clear_strip(i0, j0, i0 + 1, j1) && !opening_edge(true, i0, 0, j0, j1)) ||
           (clear_strip(i1 - 1, j0, i1, j1) && !opening_edge(true, i1, 1, j0, j1)) ||
           (clear_strip(i0, j0, i1, j0 + 1) && !opening_edge(false, j0, 0, i0, i1)) ||
           (clear_strip(i0, j1 - 1, i1, j1) && !opening_edge(false, j1, 1, i0, i1));
  };
  int best = 0;
  double best_area = 0;
  int b[4] = {0, 0, 0, 0};
  for (int i0 = 0; i0 < nx; ++i0)
    for (int i1 = i0 + 1; i1 <= nx; ++i1)
      for (int j0 = 0; j0 < ny; ++j0)
        for (int j1 = j0 + 1; j1 <= ny; ++j1) {
          if (wall_strip(i0, j0, i1, j1)) continue;
          const int n_in = block(in, i0, j0, i1, j1);
          const int n = block(off, i0, j0, i1, j1);
          // A few inliers among many features seen through the opening do not make it wall:
          // features on the inner faces near the front edge, within the wall's thickness behind
          // it, fit the wall's homography (issue 15, seed 9805: one such inlier among the
          // opening's off-wall features refused the opening).
          if (n_in > p.block_inlier_share * n) {
            if (p.block_inlier_share > 0) continue;
            break;  // growing j1 only adds inliers
          }
          const double area = (xc[i1] - xc[i0]) * (yc[j1] - yc[j0]);
          // Ties: the larger block. The frame's inner faces (wall thickness) hold no wall
          // inliers, so their far edges bound a smaller block with the same features; the
          // opening in the wall plane is bounded by the near edges.
          if (n > best || (n == best && n > 0 && area > best_area)) {
            best = n, best_area = area;
            b[0] = i0, b[1] = j0, b[2] = i1, b[3] = j1;
          }
        }
  out.estimate.n_inliers_target = best;
  if (best < p.min_outliers) {
    out.reason = Reason::kNoOpening;
    return out;
  }
  for (size_t k = 0; k < c.size(); ++k)
    if (off_wall(k)) {
      const int i = cell_of(xc, c.u2[k].x()), j = cell_of(yc, c.u2[k].y());
      if (i >= b[0] && i < b[2] && j >= b[1] && j < b[3]) out.labels[k] = Label::kTarget;
    }
  double left = xc[b[0]], right = xc[b[2]], top = yc[b[1]], bottom = yc[b[3]];
  // Each side of the block out across the wall's inner face to its front edge, on the middle
  // of the side (the corners hold the neighbouring faces too).
  if (!mask.empty() && p.max_wall_thickness_m > 0 && geometry.camera) {
    const double w = right - left, h = bottom - top;
    auto span = [](double from, double to, int n) {
      return std::pair{std::clamp(static_cast<int>(std::ceil(from)), 0, n - 1),
                       std::clamp(static_cast<int>(std::floor(to)), 0, n - 1)};
    };
    const auto [y_lo, y_hi] = span(top + 0.1 * h, bottom - 0.1 * h, mask.rows);
    const auto [x_lo, x_hi] = span(left + 0.1 * w, right - 0.1 * w, mask.cols);
    const double y_mid = 0.5 * (top + bottom), x_mid = 0.5 * (left + right);
    // The wall lies outside the block on every side (not read from the mask beside the cut: a
    // flat room next to a cut on the face's far edge leaves the mask clear on the opening's side
    // too; issue 15, ingress_photo seed 10411).
    const double l = face_front_edge(-1, true, left, 0, y_mid, y_lo, y_hi, geometry, p);
    const double r = face_front_edge(+1, true, right, 0, y_mid, y_lo, y_hi, geometry, p);
    const double t = face_front_edge(-1, false, top, 0, x_mid, x_lo, x_hi, geometry, p);
    const double bo = face_front_edge(+1, false, bottom, 0, x_mid, x_lo, x_hi, geometry, p);
    left = l, right = r, top = t, bottom = bo;
  }
  const Vector2d centre(0.5 * (left + right), 0.5 * (top + bottom));
  auto on_wall = [&](const Vector2d& px) {
    return compute_waypoint(plane, c.camera->ray(px), c.pose_1, c.pose_2, *c.mount,
                            params.waypoint);
  };
  const auto w_c = on_wall(centre);
  const auto w_l = on_wall({left, centre.y()}), w_r = on_wall({right, centre.y()});
  const auto w_t = on_wall({centre.x(), top}), w_b = on_wall({centre.x(), bottom});
  for (const auto* w : {&w_c, &w_l, &w_r, &w_t, &w_b})
    if (!*w) {
      out.reason = w->reason();
      return out;
    }
  TargetEstimate& e = out.estimate;
  e.p_W = w_c->p_W;
  e.n_W = w_c->n_W;
  e.pixel = centre;
  e.size_m[0] = (w_r->p_W - w_l->p_W).norm();
  e.size_m[1] = (w_b->p_W - w_t->p_W).norm();
  e.outline = {{left, top}, {right, top}, {right, bottom}, {left, bottom}};
  if (e.size_m[0] < p.min_size_m || e.size_m[1] < p.min_size_m) {
    out.reason = Reason::kNoOpening;
    return out;
  }
  // What is seen through an opening lies behind the wall. When the wall plane is something
  // seen through the opening instead (the nearer of two planes can still be one beyond the
  // wall when the wall itself has too few matches for a plane), the features in the block are
  // the wall itself, in front of that plane: no opening in this frame. The share is of the
  // block's matches that have a 3-D point: a mismatch has none, wherever its rays cross.
  int behind = 0, in_block = 0;
  std::vector<double> behind_parallax_px;
  for (size_t k = 0; k < c.size(); ++k) {
    const auto& X_W = X_W_match[k];
    if (out.labels[k] != Label::kTarget || !X_W) continue;
    ++in_block;
    if (e.n_W.dot(*X_W - e.p_W) < -p.behind_margin_m) {
      ++behind;
      behind_parallax_px.push_back(
          (c.x2[k] - (fit->H * c.x1[k].homogeneous()).hnormalized()).norm());
    }
  }
  if (p.min_behind_share > 0 &&
      (behind < p.min_outliers || behind < p.min_behind_share * in_block)) {
    out.reason = Reason::kNoOpening;
    return out;
  }
  // A block reaching the image border has no cut there: the opening may go on out of view, so
  // its centre and size are not known (issue 15: at the refinement's vantages the family's
  // larger openings overflowed the view, and the visible part's centre, up to 40 cm off, was
  // averaged into the estimate). Reported as a partial view, which locates it but is never
  // averaged (as the landing platform's, landing_target.cpp).
  const bool cut = b[0] == 0 || b[1] == 0 || b[2] == nx || b[3] == ny;
  // A partial view must show what a whole opening shows at one of its corners at least: the
  // wall beyond two of its sides, a hole's concave corner (two adjacent sides) or its two
  // edges in one direction (opposite sides). The wall's inliers beyond a side, over the block's
  // span along it, are the evidence that side is the wall's edge (issue 15,
  // ingress_solid_photo: the false targets' blocks ran to the image border on three sides, the
  // wall beyond the fourth: the space past the wall's end or above its top, or a poor
  // homography's stray wall features; autonomy then refined on them for 60 s). The space past
  // the wall's end and above its top has the wall beyond neither of its two sides in view.
  const int k_frame = p.partial_frame_inliers;
  const int framed = (b[0] > 0 && block(in, 0, b[1], b[0], b[3]) >= k_frame) +
                     (b[2] < nx && block(in, b[2], b[1], nx, b[3]) >= k_frame) +
                     (b[1] > 0 && block(in, b[0], 0, b[2], b[1]) >= k_frame) +
                     (b[3] < ny && block(in, b[0], b[3], b[2], ny) >= k_frame);
  if (cut && p.border_is_partial && k_frame > 0 && framed < 2) {
    out.reason = Reason::kNoOpening;
    return out;
  }
  // And its features must lie well behind the wall's own features, triangulated with motion
  // capture's poses, not only behind the plane the homography's decomposition gives: a poor
  // homography (few inliers, its plane in front of the wall) leaves the wall's own features off
  // it, all "behind" its plane (issue 15, ingress_solid_photo: seeds 9004 and 3000, the false
  // blocks' features 18 and 15 cm behind the plane, 3 and 5 cm behind the wall's inliers'
  // median; seed 3015, bands across the image with the plane 27-46 cm in front of the wall).
  if (cut && p.border_is_partial && p.partial_behind_margin_m > 0) {
    auto offset = [&](size_t k) -> std::optional<double> {
      const auto& X_W = X_W_match[k];
      if (!X_W) return std::nullopt;
      return e.n_W.dot(*X_W - e.p_W);
    };
    std::vector<double> wall_offset;
    for (size_t k = 0; k < c.size(); ++k)
      if (fit->inlier[k])
        if (const auto d = offset(k)) wall_offset.push_back(*d);
    std::vector<double> block_offset;
    for (size_t k = 0; k < c.size(); ++k)
      if (out.labels[k] == Label::kTarget)
        if (const auto d = offset(k)) block_offset.push_back(*d);
    auto median = [](std::vector<double>& v) {
      std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
      return v[v.size() / 2];
    };
    // The median, not a share: an opening's inner faces (jambs, sill) lie within the wall's
    // thickness behind it, and at the vantages they can hold a third of the block's features.
    if (wall_offset.empty() || static_cast<int>(block_offset.size()) < p.min_outliers ||
        median(block_offset) > median(wall_offset) - p.partial_behind_margin_m) {
      out.reason = Reason::kNoOpening;
      return out;
    }
  }
  // The mask shows the view beyond the opening only where its texture, moved by the parallax
  // against the wall, differs from itself: bands about its edges as wide as the displacement,
  // which the closing joins across parallax_close_px. Moved by less, the smooth parts of what is
  // seen through the opening stay wall and the block covers part of it (issue 15, ingress_photo
  // seed 9401: hovering at the vantages, the room moved a few pixels against the wall in most
  // frames, their blocks held part of the opening, and their median refused it). The outline of
  // such a frame is not a measurement of the opening, but it is the opening, checked as a whole one
  // is: it locates it (autonomy keeps it in sight and never averages it).
  if (!cut && p.min_opening_parallax_px > 0) {
    auto& v = behind_parallax_px;
    const auto mid = v.begin() + v.size() / 2;
    if (!v.empty()) std::nth_element(v.begin(), mid, v.end());
    if (v.empty() || *mid < p.min_opening_parallax_px) {
      out.reason = Reason::kLowParallax;
      return out;
    }
  }
  out.reason = cut && p.border_is_partial ? Reason::kPartialView : Reason::kOk;
  return out;
}

}  // namespace alight::vision
