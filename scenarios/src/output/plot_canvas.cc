#include "hpa/scenarios/plot_canvas.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

namespace hpa {
namespace {

const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kGrid(225, 225, 225);
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

// A "nice" tick step for a range (1, 2 or 5 times a power of ten).
double TickStep(double range) {
  const double raw = range / 5.0;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (raw <= m * mag) return m * mag;
  }
  return 10 * mag;
}

std::string Label(double v, double step) {
  char buf[32];
  const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, std::abs(v) < 1e-12 ? 0.0 : v);
  return buf;
}

}  // namespace

cv::Mat BlankFigure(int width_px, int height_px) {
  return cv::Mat(height_px, width_px, CV_8UC3, cv::Scalar(255, 255, 255));
}

cv::Scalar SeriesColour(int i) {
  static const cv::Scalar kColours[] = {{180, 119, 31}, {14, 127, 255},  {44, 160, 44},
                                        {40, 39, 214},  {189, 103, 148}, {75, 86, 140}};
  return kColours[i % 6];
}

PlotPanel::PlotPanel(cv::Mat* image, cv::Rect area, std::string title, std::string x_label,
                     std::string y_label)
    : image_(image),
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

void PlotPanel::DrawAxes() {
  // grid and tick labels
  const double xs = TickStep(x_max_ - x_min_), ys = TickStep(y_max_ - y_min_);
  for (double x = std::ceil(x_min_ / xs) * xs; x <= x_max_ + 1e-9; x += xs) {
    const cv::Point p = ToPixel(x, y_min_);
    cv::line(*image_, cv::Point(p.x, plot_.y), p, kGrid, 1);
    cv::putText(*image_, Label(x, xs), cv::Point(p.x - 12, p.y + 18), kFont, 0.4, kBlack, 1,
                cv::LINE_AA);
  }
  for (double y = std::ceil(y_min_ / ys) * ys; y <= y_max_ + 1e-9; y += ys) {
    const cv::Point p = ToPixel(x_min_, y);
    cv::line(*image_, p, cv::Point(plot_.x + plot_.width, p.y), kGrid, 1);
    cv::putText(*image_, Label(y, ys), cv::Point(area_.x + 8, p.y + 4), kFont, 0.4, kBlack, 1,
                cv::LINE_AA);
  }
  cv::rectangle(*image_, plot_, kBlack, 1);
  cv::putText(*image_, title_, cv::Point(plot_.x + 100, area_.y + 20), kFont, 0.55, kBlack, 1,
              cv::LINE_AA);
  cv::putText(*image_, x_label_,
              cv::Point(plot_.x + plot_.width / 2 - 30, plot_.y + plot_.height + 38), kFont, 0.45,
              kBlack, 1, cv::LINE_AA);
  cv::putText(*image_, y_label_, cv::Point(area_.x + 8, plot_.y - 8), kFont, 0.45, kBlack, 1,
              cv::LINE_AA);
}

void PlotPanel::ShadeX(double x0, double x1, const cv::Scalar& colour) {
  x0 = std::max(x0, x_min_);
  x1 = std::min(x1, x_max_);
  if (x1 <= x0) return;
  const cv::Point a = ToPixel(x0, y_max_), b = ToPixel(x1, y_min_);
  cv::Mat roi = (*image_)(cv::Rect(a, b) & plot_);
  cv::Mat overlay(roi.size(), roi.type(), colour);
  cv::addWeighted(overlay, 0.35, roi, 0.65, 0, roi);
}

void PlotPanel::Line(const std::vector<double>& x, const std::vector<double>& y,
                     const cv::Scalar& colour, int thickness, bool dashed) {
  cv::Mat clip = (*image_)(plot_);
  const cv::Point offset(plot_.x, plot_.y);
  for (size_t i = 1; i < std::min(x.size(), y.size()); ++i) {
    if (!std::isfinite(y[i - 1]) || !std::isfinite(y[i])) continue;
    if (dashed && (i / 6) % 2 == 1) continue;
    cv::line(clip, ToPixel(x[i - 1], y[i - 1]) - offset, ToPixel(x[i], y[i]) - offset, colour,
             thickness, cv::LINE_AA);
  }
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
  }
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
  }
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f", v_max);
  cv::putText(*image_, buf, cv::Point(x - 30, top + 8), kFont, 0.4, kBlack, 1, cv::LINE_AA);
  std::snprintf(buf, sizeof(buf), "%.1f", v_min);
  cv::putText(*image_, buf, cv::Point(x - 30, top + h), kFont, 0.4, kBlack, 1, cv::LINE_AA);
  cv::putText(*image_, label, cv::Point(x - 60, top + h / 2), kFont, 0.4, kBlack, 1, cv::LINE_AA);
}

void PlotPanel::Legend(const std::vector<std::pair<std::string, cv::Scalar>>& entries) {
  int y = plot_.y + 18;
  for (const auto& [name, colour] : entries) {
    cv::line(*image_, cv::Point(plot_.x + 10, y - 4), cv::Point(plot_.x + 35, y - 4), colour, 3);
    cv::putText(*image_, name, cv::Point(plot_.x + 42, y), kFont, 0.45, kBlack, 1, cv::LINE_AA);
    y += 18;
  }
}

void PlotPanel::ErrorBars(const std::vector<double>& x, const std::vector<double>& y,
                          const std::vector<double>& low, const std::vector<double>& high,
                          const cv::Scalar& colour) {
  for (size_t i = 0; i < x.size(); ++i) {
    cv::line(*image_, ToPixel(x[i], low[i]), ToPixel(x[i], high[i]), colour, 1, cv::LINE_AA);
    cv::circle(*image_, ToPixel(x[i], y[i]), 4, colour, cv::FILLED, cv::LINE_AA);
  }
}

}  // namespace hpa
