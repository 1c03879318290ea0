#pragma once
// How the plot canvas draws its text and lines (private to harness/reports/src/, shared by the
// figure in plot_canvas.cc and its panels in plot_panel.cc): the raster's font and colours, and
// the size the vector formats give its text.

#include <opencv2/imgproc.hpp>

namespace hpa::plot_style {

/// Text, frames and the legend's labels.
inline const cv::Scalar kBlack(0, 0, 0);
/// The panels' grid lines.
inline const cv::Scalar kGrid(225, 225, 225);
/// The raster's font (OpenCV's Hershey simplex).
inline constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
/// Hershey simplex at scale 1 is about 30 px from descender to ascender: the vector text's size
inline constexpr double kTextPxPerScale = 28.0;

}  // namespace hpa::plot_style
