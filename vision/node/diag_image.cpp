#include "vision/node/diag_image.hpp"

#include <cstdio>
#include <opencv2/imgproc.hpp>

namespace alight::vision {

cv::Mat draw_diag_image(const cv::Mat& gray, const FrameResult& r) {
  cv::Mat img;
  if (gray.empty()) {
    img = cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(0));
  } else if (gray.channels() == 1) {
    cv::cvtColor(gray, img, cv::COLOR_GRAY2BGR);
  } else {
    img = gray.clone();
  }
  auto pt = [](const Vector2d& p) { return cv::Point(cvRound(p.x()), cvRound(p.y())); };
  for (const auto& p : r.features_px) cv::circle(img, pt(p), 1, cv::Scalar(160, 160, 160), -1);
  for (const auto& s : r.lines)
    cv::line(img, {s[0], s[1]}, {s[2], s[3]}, cv::Scalar(0, 200, 255), 1, cv::LINE_AA);
  for (size_t i = 0; i < r.matched_px.size() && i < r.labels.size(); ++i) {
    const cv::Scalar colour = r.labels[i] == Label::kDominant ? cv::Scalar(0, 200, 0)
                              : r.labels[i] == Label::kTarget ? cv::Scalar(0, 0, 255)
                                                              : cv::Scalar(255, 80, 0);
    cv::circle(img, pt(r.matched_px[i]), 3, colour, 1, cv::LINE_AA);
  }
  if (r.found()) {
    const auto& o = r.target.outline;
    for (size_t i = 0; i < o.size(); ++i)
      cv::line(img, pt(o[i]), pt(o[(i + 1) % o.size()]), cv::Scalar(0, 0, 255), 2, cv::LINE_AA);
    cv::drawMarker(img, pt(r.target.pixel), cv::Scalar(0, 255, 255), cv::MARKER_CROSS, 20, 2);
  }
  char text[160];
  if (r.found())
    std::snprintf(text, sizeof text, "#%lld OK  %.2f %.2f %.2f m  h %.3f  size %.3f x %.3f",
                  static_cast<long long>(r.seq), r.target.p_W.x(), r.target.p_W.y(),
                  r.target.p_W.z(), r.target.height_m, r.target.size_m[0], r.target.size_m[1]);
  else
    std::snprintf(text, sizeof text, "#%lld %s  feat %d match %d", static_cast<long long>(r.seq),
                  to_string(r.reason), r.n_features, r.n_matches);
  cv::putText(img, text, {8, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 3);
  cv::putText(img, text, {8, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 1);
  return img;
}

}  // namespace alight::vision
