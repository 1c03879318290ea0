#pragma once
// A small line-chart canvas: axes with ticks, lines, shaded intervals, coloured scatter paths,
// legends. Each figure is drawn once into a raster (OpenCV, for PNG) and a list of vector
// primitives (cairo, for SVG and PDF, which OpenCV cannot write), and records the data of every
// series it draws, written beside the plot as CSV. Used for the run, comparison and sweep plots.

#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

namespace hpa {

/// The file format of a plot.
enum class PlotFormat { kPng, kSvg, kPdf };

/// "png" | "svg" | "pdf" to a format; throws InputError (key `option`) for anything else.
PlotFormat ParsePlotFormat(const std::string& text, const std::string& option = "--plot-format");

/// The file extension of a format, without the dot.
const char* PlotExtension(PlotFormat format);

/// Every file a figure written to STEM may leave: STEM.png, .svg, .pdf, STEM.csv and
/// STEM.shading.csv (so a rerun can remove what an earlier one wrote).
std::vector<std::string> PlotFiles(const std::string& stem);

/// One figure: its raster, its vector primitives and the data of its series.
class Figure {
 public:
  /// A white figure of the given size (pixels; the vector formats use the same units as points).
  Figure(int width_px, int height_px);

  /// Writes STEM.png|svg|pdf and STEM.csv (every drawn series: panel, series, axis labels with
  /// their units, x, y and, where drawn, low, high and colour value); returns the plot's path.
  /// Throws OutputError if a file cannot be written.
  std::string Write(const std::string& stem, PlotFormat format) const;

  /// The raster (what the PNG holds).
  cv::Mat& image() { return image_; }

  /// Text outside any panel (a header, a note) with its baseline's left end at `at` (pixels).
  void Caption(const cv::Point& at, const std::string& text, double scale = 0.5);

  /// A legend outside the panels, shared by all of them: its entries side by side from
  /// `top_left` (pixels), wrapping at the figure's right edge, each drawn in the dash of the
  /// figure's lines of its colour; each name also names every unnamed series of its colour in
  /// the CSV. Returns the height it took (pixels).
  int Legend(const cv::Point& top_left,
             const std::vector<std::pair<std::string, cv::Scalar>>& entries);

  /// A stroked polyline in figure pixels (clipped to `clip` if it has an area).
  struct Stroke {
    std::vector<cv::Point2d> points;
    cv::Scalar colour;  // BGR
    double width_px = 1.0;
    int dash = 0;  // 0 solid, 1 dashed, 2 dotted
    cv::Rect clip;
  };
  /// A filled shape: a rectangle (radius 0) or a disc at the rectangle's centre.
  struct Fill {
    cv::Rect2d rect;
    cv::Scalar colour;
    double alpha = 1.0;
    double radius_px = 0.0;
  };
  /// Text at a baseline-left point.
  struct Text {
    cv::Point2d at;
    std::string text;
    double size_px = 12.0;
  };
  /// The data of one drawn series (for the CSV).
  struct Series {
    std::string panel, name, x_label, y_label;
    cv::Scalar colour;
    bool dotted = false;  // drawn dotted (a reference): named "<legend name> (dotted)"
    std::vector<double> x, y, low, high, value;
  };

  /// One shaded x interval of a panel, in data units (for the shading CSV).
  struct Shade {
    std::string panel, label;
    double x0 = 0.0, x1 = 0.0;
    cv::Scalar colour;
  };

  std::vector<Stroke> strokes;
  std::vector<Fill> fills;
  std::vector<Shade> shades;
  std::vector<Text> texts;
  std::vector<Series> series;
  // drawing order across the three primitive lists: (kind 0 stroke, 1 fill, 2 text, index)
  std::vector<std::pair<int, size_t>> order;

 private:
  cv::Mat image_;
};

/// One panel of a figure: data coordinates mapped onto a pixel rectangle of the image.
class PlotPanel {
 public:
  /// Panel in `figure` at `area` (pixels), titled, with axis labels (their units in brackets).
  PlotPanel(Figure* figure, cv::Rect area, std::string title, std::string x_label,
            std::string y_label);

  /// Data range; call before drawing (or use FitRange).
  void SetRange(double x_min, double x_max, double y_min, double y_max);
  /// Range covering all the series given (with 5 % margin on y).
  void FitRange(const std::vector<std::vector<double>>& xs,
                const std::vector<std::vector<double>>& ys);
  /// Frame, grid, ticks, title and labels.
  void DrawAxes();
  /// Shades x in [x0, x1) over the full height (e.g. slack intervals); `label` names what the
  /// shade means in the shading CSV written beside the plot ("slack", "re-taut").
  void ShadeX(double x0, double x1, const cv::Scalar& colour, const std::string& label = "");
  /// Polyline of (x, y): dotted if `dashed` (a reference), else solid for the panel's first
  /// colour, dashed for its second, and so on, so series that overlap stay apart.
  void Line(const std::vector<double>& x, const std::vector<double>& y, const cv::Scalar& colour,
            int thickness = 2, bool dashed = false);
  /// Points coloured by value through the "turbo" colormap between v_min and v_max.
  void ColouredPath(const std::vector<double>& x, const std::vector<double>& y,
                    const std::vector<double>& value, double v_min, double v_max);
  /// Vertical colour bar at the right of the panel.
  void ColourBar(double v_min, double v_max, const std::string& label);
  /// Legend entries in the top-left corner (each drawn in its series' dash; the names also
  /// name the series of that colour in the CSV).
  void Legend(const std::vector<std::pair<std::string, cv::Scalar>>& entries);
  /// Error bars (x, low, high) as vertical segments with markers at y.
  void ErrorBars(const std::vector<double>& x, const std::vector<double>& y,
                 const std::vector<double>& low, const std::vector<double>& high,
                 const cv::Scalar& colour);

 private:
  cv::Point ToPixel(double x, double y) const;
  cv::Point2d ToPoint(double x, double y) const;  // unrounded, for the vector primitives
  void AddStroke(Figure::Stroke stroke);
  void AddText(const cv::Point& at, const std::string& text, double scale);
  Figure::Series& AddSeries(const cv::Scalar& colour);

  Figure* figure_;
  cv::Mat* image_;
  std::vector<cv::Scalar> colours_;  // colours of the panel's Line series, in order
  cv::Rect area_;                    // whole panel
  cv::Rect plot_;                    // inner plotting rectangle
  std::string title_, x_label_, y_label_;
  double x_min_ = 0, x_max_ = 1, y_min_ = 0, y_max_ = 1;
};

/// Distinct line colours (BGR) for series i.
cv::Scalar SeriesColour(int i);

}  // namespace hpa
