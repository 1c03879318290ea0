// One panel of a figure (PlotPanel, hpa/scenarios/plot_canvas.h): its data range mapped onto its
// pixel rectangle, its axes with ticks, and what it draws (lines, shaded intervals, coloured
// paths, a colour bar, a legend, error bars), each into the raster and the vector primitives.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <string>
#include <utility>
#include <vector>

#include "hpa/scenarios/plot_canvas.h"
#include "plot_style.h"

namespace hpa {
namespace {

using plot_style::kBlack;
using plot_style::kFont;
using plot_style::kGrid;
using plot_style::kTextPxPerScale;

// A "nice" tick step for a range (1, 2 or 5 times a power of ten).
double TickStep(double range) {
  const double raw = range / 5.0;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (raw <= m * mag) return m * mag;
  }
  return 10 * mag;
}

// A tick's label: v with the decimals the tick step needs.
std::string Label(double v, double step) {
  char buf[32];
  const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, std::abs(v) < 1e-12 ? 0.0 : v);
  return buf;
}

}  // namespace

PlotPanel::PlotPanel(Figure* figure, cv::Rect area, std::string title, std::string x_label,
                     std::string y_label)
    : figure_(figure),
      image_(&figure->image()),
      area_(area),
      title_(std::move(title)),
      x_label_(std::move(x_label)),
      y_label_(std::move(y_label)) {
  plot_ = cv::Rect(area.x + 70, area.y + 30, area.width - 90, area.height - 75);
}

void PlotPanel::SetRange(double x_min, double x_max, double y_min, double y_max) {
  if (x_max <= x_min) x_max = x_min + 1.0;
  if (y_max <= y_min) {
    y_min -= 0.5;
    y_max += 0.5;
  }
  x_min_ = x_min;
  x_max_ = x_max;
  y_min_ = y_min;
  y_max_ = y_max;
}

void PlotPanel::FitRange(const std::vector<std::vector<double>>& xs,
                         const std::vector<std::vector<double>>& ys) {
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const auto& x : xs) {
    for (double v : x) {
      if (std::isfinite(v)) x0 = std::min(x0, v), x1 = std::max(x1, v);
    }
  }
  for (const auto& y : ys) {
    for (double v : y) {
      if (std::isfinite(v)) y0 = std::min(y0, v), y1 = std::max(y1, v);
    }
  }
  if (x0 > x1) x0 = 0, x1 = 1;
  if (y0 > y1) y0 = 0, y1 = 1;
  const double margin = 0.05 * std::max(y1 - y0, 1e-3);
  SetRange(x0, x1, y0 - margin, y1 + margin);
}

cv::Point PlotPanel::ToPixel(double x, double y) const {
  const double u = (x - x_min_) / (x_max_ - x_min_);
  const double v = (y - y_min_) / (y_max_ - y_min_);
  return cv::Point(plot_.x + static_cast<int>(std::lround(u * plot_.width)),
                   plot_.y + plot_.height - static_cast<int>(std::lround(v * plot_.height)));
}

cv::Point2d PlotPanel::ToPoint(double x, double y) const {
  const double u = (x - x_min_) / (x_max_ - x_min_);
  const double v = (y - y_min_) / (y_max_ - y_min_);
  return cv::Point2d(plot_.x + u * plot_.width, plot_.y + plot_.height - v * plot_.height);
}

void PlotPanel::AddStroke(Figure::Stroke stroke) {
  figure_->order.emplace_back(0, figure_->strokes.size());
  figure_->strokes.push_back(std::move(stroke));
}

void PlotPanel::AddText(const cv::Point& at, const std::string& text, double scale) {
  cv::putText(*image_, text, at, kFont, scale, kBlack, 1, cv::LINE_AA);
  figure_->order.emplace_back(2, figure_->texts.size());
  figure_->texts.push_back({cv::Point2d(at.x, at.y), text, kTextPxPerScale * scale});
}

Figure::Series& PlotPanel::AddSeries(const cv::Scalar& colour) {
  Figure::Series s;
  s.panel = title_;
  s.x_label = x_label_;
  s.y_label = y_label_;
  s.colour = colour;
  figure_->series.push_back(std::move(s));
  return figure_->series.back();
}

void PlotPanel::DrawAxes() {
  // grid and tick labels
  const double xs = TickStep(x_max_ - x_min_), ys = TickStep(y_max_ - y_min_);
  for (double x = std::ceil(x_min_ / xs) * xs; x <= x_max_ + 1e-9; x += xs) {
    const cv::Point p = ToPixel(x, y_min_);
    cv::line(*image_, cv::Point(p.x, plot_.y), p, kGrid, 1);
    AddStroke({{cv::Point2d(p.x, plot_.y), cv::Point2d(p.x, p.y)}, kGrid, 1.0, 0, cv::Rect()});
    AddText(cv::Point(p.x - 12, p.y + 18), Label(x, xs), 0.4);
  }
  for (double y = std::ceil(y_min_ / ys) * ys; y <= y_max_ + 1e-9; y += ys) {
    const cv::Point p = ToPixel(x_min_, y);
    cv::line(*image_, p, cv::Point(plot_.x + plot_.width, p.y), kGrid, 1);
    AddStroke({{cv::Point2d(p.x, p.y), cv::Point2d(plot_.x + plot_.width, p.y)},
               kGrid,
               1.0,
               0,
               cv::Rect()});
    AddText(cv::Point(area_.x + 8, p.y + 4), Label(y, ys), 0.4);
  }
  cv::rectangle(*image_, plot_, kBlack, 1);
  const double x0 = plot_.x, y0 = plot_.y, x1 = plot_.x + plot_.width, y1 = plot_.y + plot_.height;
  AddStroke({{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}, {x0, y0}}, kBlack, 1.0, 0, cv::Rect()});
  AddText(cv::Point(plot_.x + 100, area_.y + 20), title_, 0.55);
  AddText(cv::Point(plot_.x + plot_.width / 2 - 30, plot_.y + plot_.height + 38), x_label_, 0.45);
  AddText(cv::Point(area_.x + 8, plot_.y - 8), y_label_, 0.45);
}

void PlotPanel::ShadeX(double x0, double x1, const cv::Scalar& colour, const std::string& label) {
  x0 = std::max(x0, x_min_);
  x1 = std::min(x1, x_max_);
  if (x1 <= x0) return;
  figure_->shades.push_back({title_, label, x0, x1, colour});
  const cv::Point a = ToPixel(x0, y_max_), b = ToPixel(x1, y_min_);
  cv::Mat roi = (*image_)(cv::Rect(a, b) & plot_);
  cv::Mat overlay(roi.size(), roi.type(), colour);
  cv::addWeighted(overlay, 0.35, roi, 0.65, 0, roi);
  const cv::Rect r = cv::Rect(a, b) & plot_;
  figure_->order.emplace_back(1, figure_->fills.size());
  figure_->fills.push_back({cv::Rect2d(r.x, r.y, r.width, r.height), colour, 0.35, 0.0});
}

void PlotPanel::Line(const std::vector<double>& x, const std::vector<double>& y,
                     const cv::Scalar& colour, int thickness, bool dashed) {
  // explicitly dashed lines (references) dotted; the others by their colour's order in the
  // panel: the first solid, the second dashed, and so on
  size_t colour_index = 0;
  while (colour_index < colours_.size() && colours_[colour_index] != colour) ++colour_index;
  if (colour_index == colours_.size() && !dashed) colours_.push_back(colour);
  const int dash = dashed ? 2 : static_cast<int>(colour_index % 2);
  cv::Mat clip = (*image_)(plot_);
  const cv::Point offset(plot_.x, plot_.y);
  const size_t n = std::min(x.size(), y.size());
  // the raster's dashes by sample count (dashed 6 on 6 off, dotted 3 on 3 off)
  const size_t period = dash == 1 ? 6 : 3;
  for (size_t i = 1; i < n; ++i) {
    if (!std::isfinite(y[i - 1]) || !std::isfinite(y[i])) continue;
    if (dash > 0 && (i / period) % 2 == 1) continue;
    cv::line(clip, ToPixel(x[i - 1], y[i - 1]) - offset, ToPixel(x[i], y[i]) - offset, colour,
             thickness, cv::LINE_AA);
  }
  Figure::Stroke stroke{{}, colour, static_cast<double>(thickness), dash, plot_};
  for (size_t i = 0; i < n; ++i) {
    stroke.points.push_back(std::isfinite(y[i]) ? ToPoint(x[i], y[i])
                                                : cv::Point2d(std::nan(""), std::nan("")));
  }
  AddStroke(std::move(stroke));
  Figure::Series& s = AddSeries(colour);
  s.dotted = dash == 2;
  s.x.assign(x.begin(), x.begin() + static_cast<long>(n));
  s.y.assign(y.begin(), y.begin() + static_cast<long>(n));
}

void PlotPanel::ColouredPath(const std::vector<double>& x, const std::vector<double>& y,
                             const std::vector<double>& value, double v_min, double v_max) {
  cv::Mat ramp(1, 256, CV_8UC1);
  for (int i = 0; i < 256; ++i) ramp.at<uchar>(i) = static_cast<uchar>(i);
  cv::Mat colours;
  cv::applyColorMap(ramp, colours, cv::COLORMAP_TURBO);
  cv::Mat clip = (*image_)(plot_);
  const cv::Point offset(plot_.x, plot_.y);
  for (size_t i = 1; i < x.size(); ++i) {
    const double f = std::clamp((value[i] - v_min) / std::max(v_max - v_min, 1e-9), 0.0, 1.0);
    const cv::Vec3b c = colours.at<cv::Vec3b>(static_cast<int>(f * 255));
    cv::line(clip, ToPixel(x[i - 1], y[i - 1]) - offset, ToPixel(x[i], y[i]) - offset,
             cv::Scalar(c[0], c[1], c[2]), 3, cv::LINE_AA);
    AddStroke({{ToPoint(x[i - 1], y[i - 1]), ToPoint(x[i], y[i])},
               cv::Scalar(c[0], c[1], c[2]),
               3.0,
               0,
               plot_});
  }
  Figure::Series& s = AddSeries(cv::Scalar(0, 0, 0));
  s.name = "path coloured by value";
  s.x = x;
  s.y = y;
  s.value = value;
}

void PlotPanel::ColourBar(double v_min, double v_max, const std::string& label) {
  cv::Mat ramp(1, 256, CV_8UC1);
  for (int i = 0; i < 256; ++i) ramp.at<uchar>(i) = static_cast<uchar>(i);
  cv::Mat colours;
  cv::applyColorMap(ramp, colours, cv::COLORMAP_TURBO);
  const int x = plot_.x + plot_.width - 22, top = plot_.y + 10, h = plot_.height - 20;
  for (int i = 0; i < h; ++i) {
    const cv::Vec3b c = colours.at<cv::Vec3b>(255 - i * 255 / std::max(h - 1, 1));
    cv::line(*image_, cv::Point(x, top + i), cv::Point(x + 12, top + i),
             cv::Scalar(c[0], c[1], c[2]));
    figure_->order.emplace_back(1, figure_->fills.size());
    figure_->fills.push_back(
        {cv::Rect2d(x, top + i, 12, 1.0), cv::Scalar(c[0], c[1], c[2]), 1.0, 0.0});
  }
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f", v_max);
  AddText(cv::Point(x - 30, top + 8), buf, 0.4);
  std::snprintf(buf, sizeof(buf), "%.1f", v_min);
  AddText(cv::Point(x - 30, top + h), buf, 0.4);
  AddText(cv::Point(x - 60, top + h / 2), label, 0.4);
}

void PlotPanel::Legend(const std::vector<std::pair<std::string, cv::Scalar>>& entries) {
  int y = plot_.y + 18;
  for (const auto& [name, colour] : entries) {
    // the dash of this panel's series of this colour (solid if none)
    int dash = 0;
    for (const Figure::Stroke& s : figure_->strokes) {
      if (s.colour == colour && s.clip == plot_) dash = s.dash;
    }
    for (int k = 0; k < 5; ++k) {
      if (dash > 0 && k % 2 == 1) continue;
      const int a = plot_.x + 10 + 5 * k;
      cv::line(*image_, cv::Point(a, y - 4), cv::Point(dash > 0 ? a + 5 : plot_.x + 35, y - 4),
               colour, 3);
      if (dash == 0) break;
    }
    AddStroke({{cv::Point2d(plot_.x + 10, y - 4), cv::Point2d(plot_.x + 35, y - 4)},
               colour,
               3.0,
               dash,
               cv::Rect()});
    AddText(cv::Point(plot_.x + 42, y), name, 0.45);
    // the legend names this panel's series of that colour in the CSV
    for (Figure::Series& s : figure_->series) {
      if (s.panel == title_ && s.colour == colour && s.name.empty()) {
        s.name = s.dotted ? name + " (dotted)" : name;
      }
    }
    y += 18;
  }
}

void PlotPanel::ErrorBars(const std::vector<double>& x, const std::vector<double>& y,
                          const std::vector<double>& low, const std::vector<double>& high,
                          const cv::Scalar& colour) {
  for (size_t i = 0; i < x.size(); ++i) {
    cv::line(*image_, ToPixel(x[i], low[i]), ToPixel(x[i], high[i]), colour, 1, cv::LINE_AA);
    cv::circle(*image_, ToPixel(x[i], y[i]), 4, colour, cv::FILLED, cv::LINE_AA);
    AddStroke({{ToPoint(x[i], low[i]), ToPoint(x[i], high[i])}, colour, 1.0, 0, cv::Rect()});
    const cv::Point2d c = ToPoint(x[i], y[i]);
    figure_->order.emplace_back(1, figure_->fills.size());
    figure_->fills.push_back({cv::Rect2d(c.x - 4, c.y - 4, 8, 8), colour, 1.0, 4.0});
  }
  Figure::Series& s = AddSeries(colour);
  s.x = x;
  s.y = y;
  s.low = low;
  s.high = high;
}

}  // namespace hpa
