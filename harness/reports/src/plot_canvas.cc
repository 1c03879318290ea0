// The plot canvas's figure (hpa/scenarios/plot_canvas.h): the plot formats and the files a
// figure may leave, the figure with its captions and its shared legend, and the series colours.
// Its panels are in plot_panel.cc; writing it (PNG, or SVG and PDF through cairo, with the CSV of
// its data) in figure_files.cc.

#include "hpa/scenarios/plot_canvas.h"

#include <opencv2/imgproc.hpp>
#include <string>
#include <utility>
#include <vector>

#include "hpa/models/input_error.h"
#include "plot_style.h"

namespace hpa {

using plot_style::kBlack;
using plot_style::kFont;
using plot_style::kTextPxPerScale;

PlotFormat ParsePlotFormat(const std::string& text, const std::string& option) {
  if (text == "png") return PlotFormat::kPng;
  if (text == "svg") return PlotFormat::kSvg;
  if (text == "pdf") return PlotFormat::kPdf;
  throw InputError("", option, "unknown plot format '" + text + "', expected png | svg | pdf");
}

const char* PlotExtension(PlotFormat format) {
  switch (format) {
    case PlotFormat::kSvg:
      return "svg";
    case PlotFormat::kPdf:
      return "pdf";
    case PlotFormat::kPng:
      break;
  }
  return "png";
}

std::vector<std::string> PlotFiles(const std::string& stem) {
  std::vector<std::string> files;
  for (const PlotFormat f : {PlotFormat::kPng, PlotFormat::kSvg, PlotFormat::kPdf}) {
    files.push_back(stem + "." + PlotExtension(f));
  }
  files.push_back(stem + ".csv");
  files.push_back(stem + ".shading.csv");
  return files;
}

Figure::Figure(int width_px, int height_px)
    : image_(height_px, width_px, CV_8UC3, cv::Scalar(255, 255, 255)) {}

void Figure::Caption(const cv::Point& at, const std::string& text, double scale) {
  cv::putText(image_, text, at, kFont, scale, kBlack, 1, cv::LINE_AA);
  order.emplace_back(2, texts.size());
  texts.push_back({cv::Point2d(at.x, at.y), text, kTextPxPerScale * scale});
}

int Figure::Legend(const cv::Point& top_left,
                   const std::vector<std::pair<std::string, cv::Scalar>>& entries) {
  constexpr double kScale = 0.45;
  constexpr int kRow_px = 20;
  int x = top_left.x, y = top_left.y + 14;
  for (const auto& [name, colour] : entries) {
    int baseline = 0;
    const int text_px = cv::getTextSize(name, kFont, kScale, 1, &baseline).width;
    const int entry_px = 42 + text_px + 28;
    if (x > top_left.x && x + entry_px > image_.cols - 10) {  // wrap onto the next row
      x = top_left.x;
      y += kRow_px;
    }
    // the dash of the figure's data lines of this colour (solid if none)
    int dash = 0;
    for (const Stroke& s : strokes) {
      if (s.colour == colour && s.clip.area() > 0) {
        dash = s.dash;
        break;
      }
    }
    for (int k = 0; k < 5; ++k) {
      if (dash > 0 && k % 2 == 1) continue;
      const int a = x + 5 * k;
      cv::line(image_, cv::Point(a, y - 4), cv::Point(dash > 0 ? a + 5 : x + 25, y - 4), colour, 3);
      if (dash == 0) break;
    }
    order.emplace_back(0, strokes.size());
    strokes.push_back(
        {{cv::Point2d(x, y - 4), cv::Point2d(x + 25, y - 4)}, colour, 3.0, dash, cv::Rect()});
    Caption(cv::Point(x + 32, y), name, kScale);
    for (Series& s : series) {
      if (s.colour == colour && s.name.empty()) s.name = s.dotted ? name + " (dotted)" : name;
    }
    x += entry_px;
  }
  return y + 8 - top_left.y;
}

cv::Scalar SeriesColour(int i) {
  static const cv::Scalar kColours[] = {{180, 119, 31}, {14, 127, 255},  {44, 160, 44},
                                        {40, 39, 214},  {189, 103, 148}, {75, 86, 140}};
  return kColours[i % 6];
}

}  // namespace hpa
