#pragma once
// How deep a point lies inside a convex polygon (the hull of a top's matches, known_floor.cpp and
// landing_target.cpp). Inside a convex polygon the distance to the boundary is the least distance
// to its edges' lines, so each test is one multiply-add per edge with the lines prepared once;
// cv::pointPolygonTest with its distance measures every edge segment per call, and the hull
// tests ran it for every match of every top hypothesis and every sampled hull pixel.

#include <algorithm>
#include <limits>
#include <opencv2/core.hpp>
#include <vector>

namespace alight::vision {

class ConvexHullDepth {
 public:
  /// `hull`: the corners of a convex polygon in order (either turn), e.g. from cv::convexHull.
  /// Fewer than 3 corners, or no area: nothing is inside.
  explicit ConvexHullDepth(const std::vector<cv::Point2f>& hull) {
    const size_t n = hull.size();
    if (n < 3) return;
    double area2 = 0;  // twice the signed area: its sign is the turn
    for (size_t i = 0; i < n; ++i) {
      const cv::Point2f& a = hull[i];
      const cv::Point2f& b = hull[(i + 1) % n];
      area2 += double(a.x) * b.y - double(b.x) * a.y;
    }
    if (!(std::abs(area2) > 0)) return;
    const double turn = area2 > 0 ? 1.0 : -1.0;
    for (size_t i = 0; i < n; ++i) {
      const cv::Point2f& a = hull[i];
      const cv::Point2f& b = hull[(i + 1) % n];
      const double dx = double(b.x) - a.x, dy = double(b.y) - a.y;
      const double len = std::hypot(dx, dy);
      if (!(len > 0)) continue;  // a repeated corner
      // Inward unit normal: left of a->b for a positive turn, right otherwise.
      const double nx = -turn * dy / len, ny = turn * dx / len;
      lines_.push_back({nx, ny, -(nx * a.x + ny * a.y)});
    }
  }

  bool empty() const { return lines_.empty(); }

  /// Distance to the boundary for a point inside; for a point outside, a negative number
  /// (not its distance: only the sign, and every depth > m >= 0, agree with
  /// cv::pointPolygonTest). -infinity when the polygon is empty.
  double depth(double x, double y) const {
    if (lines_.empty()) return -std::numeric_limits<double>::infinity();
    double d = std::numeric_limits<double>::infinity();
    for (const Line& l : lines_) d = std::min(d, l.a * x + l.b * y + l.c);
    return d;
  }

  /// Inside by more than margin (>= 0).
  bool inside_by(double x, double y, double margin) const { return depth(x, y) > margin; }

 private:
  struct Line {
    double a, b, c;  // a x + b y + c: signed distance, positive inside
  };
  std::vector<Line> lines_;
};

}  // namespace alight::vision
