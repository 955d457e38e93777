// Ingress stage 2, the cuts: the straight lines that cut the image into cells (paper 3.3,
// Fig. 7; see cuts.hpp).
#include "vision/ingress/cuts.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <utility>

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
// the pixels searched: the whole image's would cost two passes for a few lines' pixels.
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
  // are the inner loop so a vertical line's pixels are read row by row (a column per offset
  // misses the cache on every pixel).
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
  // among those at least 0.8 of the strongest (a lower share lets the wall texture's steps
  // through; the strongest alone takes the far edges of the faces).
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
// points are the border's list rather than a scan of the whole image for them (the image's
// 300 000 pixels three times a frame). Appends (rho, theta, votes) to `out`.
void hough_lines(const std::vector<cv::Point>& px, cv::Size size, double theta_lo, double theta_hi,
                 double theta_step, int threshold, std::vector<cv::Vec3f>* out) {
  const int n_theta = cvRound((theta_hi - theta_lo) / theta_step);
  const int n_rho = 2 * (size.width + size.height) + 1;
  if (n_theta <= 0) return;
  const int stride = n_rho + 2;  // a zero bin before and after each row and angle
  std::vector<int> votes(static_cast<size_t>(n_theta + 2) * stride, 0);
  const int rho_offset = (n_rho - 1) / 2;
  // The points in float once, not once per angle.
  std::vector<float> xs(px.size()), ys(px.size());
  for (size_t i = 0; i < px.size(); ++i)
    xs[i] = static_cast<float>(px[i].x), ys[i] = static_cast<float>(px[i].y);
  float theta = static_cast<float>(theta_lo);
  for (int k = 0; k < n_theta; ++k, theta += static_cast<float>(theta_step)) {
    const float c = static_cast<float>(std::cos(static_cast<double>(theta)));
    const float s = static_cast<float>(std::sin(static_cast<double>(theta)));
    int* row = votes.data() + static_cast<size_t>(k + 1) * stride + 1 + rho_offset;
    for (size_t i = 0; i < xs.size(); ++i) ++row[cvRound(xs[i] * c + ys[i] * s)];
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

// Border pixels in cv::findNonZero's order (row by row, x increasing) and where each row's run
// starts, so the pixels near a line are looked for only in the x-range of each row that can
// hold them instead of among all of them for every line (on a busy wall the border has
// thousands of pixels and the Hough transform dozens of lines).
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

// The mask border's lines (rho, theta, votes), strongest first. The standard Hough transform
// (full lines, votes from anywhere along them) rather than the probabilistic one: the border is
// ragged by a few pixels where the view beyond the wall agrees with it by chance, which breaks a
// segment walk but barely spreads the votes. Only the angles a cut can have are voted on (near
// 0, pi and pi/2: a tenth of the 180 the full transform accumulates).
std::vector<cv::Vec3f> border_lines(const std::vector<cv::Point>& px, cv::Size size,
                                    const IngressParams& p) {
  const double tilt = p.max_line_tilt_deg * M_PI / 180.0;
  constexpr double kThetaStep = CV_PI / 180.0;
  std::vector<cv::Vec3f> lines;  // rho, theta, votes
  if (px.empty()) return lines;
  for (const auto& [lo, hi] : {std::pair{0.0, tilt + kThetaStep}, std::pair{CV_PI - tilt, CV_PI},
                               std::pair{CV_PI / 2 - tilt, CV_PI / 2 + tilt + kThetaStep}})
    hough_lines(px, size, lo, hi, kThetaStep, p.hough_threshold, &lines);
  std::stable_sort(lines.begin(), lines.end(),
                   [](const cv::Vec3f& l, const cv::Vec3f& r) { return l[2] > r[2]; });
  return lines;
}

// A border line refined on the border pixels near it: across = a + b (along - mean_along) over
// the along-coordinates [lo, hi] its band covers, `covered` of them (a full line may hold short
// pieces).
struct BorderFit {
  bool vertical;
  double a, b, mean_along;
  int lo, hi;
  std::ptrdiff_t covered;
};

// One border side gets dozens of Hough lines (neighbouring rho and theta bins of a
// two-pixel-wide, ragged border); one that stays within kSamePx of a refined line where that
// line has border pixels would select the same pixels and give the same cut, so it is not
// refined again.
bool refined_before(const std::vector<BorderFit>& fitted, double rho, double theta, bool vertical) {
  constexpr double kSamePx = 2.0;
  // The Hough line's across-coordinate at `along`: x at row y for a vertical line.
  const double c = std::cos(theta), s = std::sin(theta);
  auto hough_across = [&](double t) { return vertical ? (rho - t * s) / c : (rho - t * c) / s; };
  return std::any_of(fitted.begin(), fitted.end(), [&](const BorderFit& f) {
    if (f.vertical != vertical) return false;
    for (const int t : {f.lo, f.hi})
      if (std::abs(hough_across(t) - (f.a + f.b * (t - f.mean_along))) > kSamePx) return false;
    return true;
  });
}

// Refines the Hough line (rho, theta) on the border pixels near it: the across-coordinate
// a + b * along fitted by least squares twice, narrowing the band; the cut is its mean (the fit
// at the centre). nullopt when no pixel is left in the band.
std::optional<BorderFit> fit_border_line(const BorderPixels& border_px, double rho, double theta,
                                         bool vertical, const cv::Mat& mask) {
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
  if (band.empty()) return std::nullopt;
  std::vector<uint8_t> covered(vertical ? mask.rows : mask.cols, 0);
  int lo = static_cast<int>(covered.size()), hi = -1;
  for (const auto* q : band) {
    covered[along(*q)] = 1;
    lo = std::min(lo, along(*q)), hi = std::max(hi, along(*q));
  }
  return BorderFit{
      vertical, a, b, mean_along, lo, hi, std::count(covered.begin(), covered.end(), 1)};
}

}  // namespace

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

void mask_cuts(const cv::Mat& mask, const IngressParams& p, std::vector<double>* x_cuts,
               std::vector<double>* y_cuts, std::vector<cv::Vec4i>* kept, const cv::Mat& image) {
  assert(mask.type() == CV_8UC1);
  assert(image.empty() || (image.type() == CV_8UC1 && image.size() == mask.size()));
  cv::Mat smooth;
  if (!image.empty() && p.snap_px > 0) cv::GaussianBlur(image, smooth, cv::Size(), 1.0);
  // The mask's border, two pixels wide and straddling it, so the mean of a border line's
  // pixels is the border itself.
  const BorderPixels border_px(mask_border_pixels(mask), mask.rows);
  const double tilt = p.max_line_tilt_deg * M_PI / 180.0;
  const double min_length = p.hough_min_length_frac * mask.cols;
  std::vector<double> xs{0.0, static_cast<double>(mask.cols)};
  std::vector<double> ys{0.0, static_cast<double>(mask.rows)};
  std::vector<BorderFit> fitted;
  for (const auto& l : border_lines(border_px.px, mask.size(), p)) {
    const double rho = l[0], theta = l[1];
    const bool vertical = std::min(theta, CV_PI - theta) <= tilt;
    if (!vertical && std::abs(theta - CV_PI / 2) > tilt) continue;
    if (refined_before(fitted, rho, theta, vertical)) continue;
    // The strongest distinct lines only: a mask left ragged all over (the view off the wall
    // with little texture, a poor homography) gives hundreds, and refining every one costs the
    // slowest frames several times the median; an opening's sides are among the strongest.
    if (static_cast<int>(fitted.size()) >= p.max_border_lines) break;
    const auto f = fit_border_line(border_px, rho, theta, vertical, mask);
    if (!f) continue;
    fitted.push_back(*f);
    if (f->covered < min_length) continue;
    double a = f->a;
    if (!smooth.empty())
      a = snap_to_edge(smooth, mask, vertical, a, f->b, f->mean_along, f->lo, f->hi, p);
    (vertical ? xs : ys).push_back(a);
    if (kept) {
      const double e0 = a + f->b * (f->lo - f->mean_along), e1 = a + f->b * (f->hi - f->mean_along);
      kept->push_back(vertical ? cv::Vec4i(cvRound(e0), f->lo, cvRound(e1), f->hi)
                               : cv::Vec4i(f->lo, cvRound(e0), f->hi, cvRound(e1)));
    }
  }
  *x_cuts = merged(xs, p.merge_px);
  *y_cuts = merged(ys, p.merge_px);
  x_cuts->front() = 0.0, x_cuts->back() = mask.cols;
  y_cuts->front() = 0.0, y_cuts->back() = mask.rows;
}

}  // namespace alight::vision
