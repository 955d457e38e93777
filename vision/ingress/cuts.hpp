#pragma once
// Ingress, stage 2 of 4 (wall -> blocks -> faces -> opening), its second part: the straight
// lines that cut the image into cells (paper 3.3, Fig. 7). The paper's are the near-vertical
// and near-horizontal edges of the grey image (Canny, then the probabilistic Hough transform of
// Matas, Galambos & Kittler, CVIU 2000, as cv::HoughLinesP); beyond the paper they are the
// off-wall mask's border (mask.hpp), which sees neither the wall's texture nor the inner faces,
// each line refined on the border's pixels and snapped to the wall's edge in the grey image.

#include <opencv2/core.hpp>
#include <vector>

#include "vision/params.hpp"

namespace alight::vision {

/// The near-vertical (x) and near-horizontal (y) cut positions of the image's straight edges
/// (Canny, probabilistic Hough), sorted, merged within merge_px, including the image borders;
/// kept_segments (optional) receives the segments kept.
void line_cuts(const cv::Mat& image, const IngressParams& params, std::vector<double>* x_cuts,
               std::vector<double>* y_cuts, std::vector<cv::Vec4i>* kept_segments);

/// The same cuts from an off-wall mask's border: the strongest max_border_lines distinct
/// standard Hough lines within max_line_tilt_deg of vertical or horizontal, each refined by a
/// least-squares fit to the border pixels along it, kept where its band covers
/// hough_min_length_frac of the image's width and, given the grey `image`, moved to the wall's
/// edge: the step in the image within snap_px on the wall's side (where the mask is clear).
void mask_cuts(const cv::Mat& mask, const IngressParams& params, std::vector<double>* x_cuts,
               std::vector<double>* y_cuts, std::vector<cv::Vec4i>* kept_segments,
               const cv::Mat& image = cv::Mat());

}  // namespace alight::vision
