#pragma once
// A small line-chart canvas drawn with OpenCV (no plotting dependency): axes with ticks, lines,
// shaded intervals, coloured scatter paths, legends. Used for the run and sweep PNGs.

#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

namespace hpa {

/// One panel of a figure: data coordinates mapped onto a pixel rectangle of the image.
class PlotPanel {
 public:
  /// Panel in `image` at `area` (pixels), titled, with axis labels.
  PlotPanel(cv::Mat* image, cv::Rect area, std::string title, std::string x_label,
            std::string y_label);

  /// Data range; call before drawing (or use FitRange).
  void SetRange(double x_min, double x_max, double y_min, double y_max);
  /// Range covering all the series given (with 5 % margin on y).
  void FitRange(const std::vector<std::vector<double>>& xs,
                const std::vector<std::vector<double>>& ys);
  /// Frame, grid, ticks, title and labels.
  void DrawAxes();
  /// Shades x in [x0, x1) over the full height (e.g. slack intervals).
  void ShadeX(double x0, double x1, const cv::Scalar& colour);
  /// Polyline of (x, y); dashed if asked.
  void Line(const std::vector<double>& x, const std::vector<double>& y, const cv::Scalar& colour,
            int thickness = 2, bool dashed = false);
  /// Points coloured by value through the "turbo" colormap between v_min and v_max.
  void ColouredPath(const std::vector<double>& x, const std::vector<double>& y,
                    const std::vector<double>& value, double v_min, double v_max);
  /// Vertical colour bar at the right of the panel.
  void ColourBar(double v_min, double v_max, const std::string& label);
  /// Legend entries in the top-left corner.
  void Legend(const std::vector<std::pair<std::string, cv::Scalar>>& entries);
  /// Error bars (x, low, high) as vertical segments with markers at y.
  void ErrorBars(const std::vector<double>& x, const std::vector<double>& y,
                 const std::vector<double>& low, const std::vector<double>& high,
                 const cv::Scalar& colour);

 private:
  cv::Point ToPixel(double x, double y) const;

  cv::Mat* image_;
  cv::Rect area_;  // whole panel
  cv::Rect plot_;  // inner plotting rectangle
  std::string title_, x_label_, y_label_;
  double x_min_ = 0, x_max_ = 1, y_min_ = 0, y_max_ = 1;
};

/// A white canvas of the given size.
cv::Mat BlankFigure(int width_px, int height_px);

/// Distinct line colours (BGR) for series i.
cv::Scalar SeriesColour(int i);

}  // namespace hpa
