#include "hpa/scenarios/plot_canvas.h"

#include <cairo-pdf.h>
#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "media.h"

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

// Hershey simplex at scale 1 is about 30 px from descender to ascender: the vector text's size
constexpr double kTextPxPerScale = 28.0;

void SetColour(cairo_t* cr, const cv::Scalar& bgr, double alpha = 1.0) {
  cairo_set_source_rgba(cr, bgr[2] / 255.0, bgr[1] / 255.0, bgr[0] / 255.0, alpha);
}

// Replays a figure's primitives on a cairo surface of the figure's size.
void Replay(const Figure& f, cairo_t* cr) {
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  for (const auto& [kind, i] : f.order) {
    cairo_save(cr);
    if (kind == 0) {
      const Figure::Stroke& s = f.strokes[i];
      if (s.clip.area() > 0) {
        cairo_rectangle(cr, s.clip.x, s.clip.y, s.clip.width, s.clip.height);
        cairo_clip(cr);
      }
      const double dashes[2][2] = {{12.0, 8.0}, {2.0, 5.0}};
      if (s.dash > 0) cairo_set_dash(cr, dashes[s.dash - 1], 2, 0.0);
      cairo_set_line_width(cr, s.width_px);
      SetColour(cr, s.colour);
      bool pen_down = false;
      for (const cv::Point2d& p : s.points) {
        if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
          pen_down = false;  // a gap in the data breaks the line
          continue;
        }
        if (pen_down) {
          cairo_line_to(cr, p.x, p.y);
        } else {
          cairo_move_to(cr, p.x, p.y);
        }
        pen_down = true;
      }
      cairo_stroke(cr);
    } else if (kind == 1) {
      const Figure::Fill& r = f.fills[i];
      SetColour(cr, r.colour, r.alpha);
      if (r.radius_px > 0) {
        cairo_arc(cr, r.rect.x + r.rect.width / 2, r.rect.y + r.rect.height / 2, r.radius_px, 0,
                  2 * M_PI);
      } else {
        cairo_rectangle(cr, r.rect.x, r.rect.y, r.rect.width, r.rect.height);
      }
      cairo_fill(cr);
    } else {
      const Figure::Text& t = f.texts[i];
      cairo_set_source_rgb(cr, 0, 0, 0);
      cairo_set_font_size(cr, t.size_px);
      cairo_move_to(cr, t.at.x, t.at.y);
      cairo_show_text(cr, t.text.c_str());
    }
    cairo_restore(cr);
  }
}

std::string CsvText(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string CsvNumber(const std::vector<double>& v, size_t i) {
  if (i >= v.size() || !std::isfinite(v[i])) return "";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.10g", v[i]);
  return buf;
}

}  // namespace

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

std::string Figure::Write(const std::string& stem, PlotFormat format) const {
  const std::string path = stem + "." + PlotExtension(format);
  if (format == PlotFormat::kPng) {
    if (!WriteImage(path, image_)) throw OutputError(path, "the PNG could not be written");
  } else {
    cairo_surface_t* surface =
        format == PlotFormat::kSvg
            ? cairo_svg_surface_create(PartialPath(path).c_str(), image_.cols, image_.rows)
            : cairo_pdf_surface_create(PartialPath(path).c_str(), image_.cols, image_.rows);
    cairo_t* cr = cairo_create(surface);
    Replay(*this, cr);
    cairo_destroy(cr);
    cairo_surface_finish(surface);
    const cairo_status_t status = cairo_surface_status(surface);
    cairo_surface_destroy(surface);
    if (status != CAIRO_STATUS_SUCCESS) {
      std::remove(PartialPath(path).c_str());
      throw OutputError(path, std::string("cairo: ") + cairo_status_to_string(status));
    }
    CommitPartial(path);
  }
  // the data, one row per point of every series, long format
  const std::string csv = stem + ".csv";
  std::ostringstream out;
  out << "panel,series,x_label,y_label,x,y,low,high,value\n";
  for (size_t k = 0; k < series.size(); ++k) {
    const Series& s = series[k];
    // an unnamed series takes the name of a named one of its colour (a legend in another
    // panel), else "series K"
    std::string name = s.name;
    for (const Series& other : series) {
      if (name.empty() && !other.name.empty() && other.colour == s.colour &&
          other.dotted == s.dotted) {
        name = other.name;
      }
    }
    if (name.empty()) name = "series " + std::to_string(k) + (s.dotted ? " (dotted)" : "");
    const std::string head = CsvText(s.panel) + "," + CsvText(name) + "," + CsvText(s.x_label) +
                             "," + CsvText(s.y_label) + ",";
    for (size_t i = 0; i < s.x.size(); ++i) {
      out << head << CsvNumber(s.x, i) << "," << CsvNumber(s.y, i) << "," << CsvNumber(s.low, i)
          << "," << CsvNumber(s.high, i) << "," << CsvNumber(s.value, i) << "\n";
    }
  }
  WriteFileAtomic(csv, out.str());
  // what the plot shades (slack intervals, re-taut marks), so a redraw shades the same spans
  // without deriving them again; no shade: no file (an older one removed)
  const std::string shading_csv = stem + ".shading.csv";
  if (shades.empty()) {
    std::remove(shading_csv.c_str());
  } else {
    std::ostringstream shading;
    shading << "panel,label,x0,x1,r,g,b\n";
    for (const Shade& sh : shades) {
      // cv::Scalar is BGR; the CSV gives RGB in 0-255
      shading << CsvText(sh.panel) << "," << CsvText(sh.label) << "," << CsvNumber({sh.x0}, 0)
              << "," << CsvNumber({sh.x1}, 0) << "," << sh.colour[2] << "," << sh.colour[1] << ","
              << sh.colour[0] << "\n";
    }
    WriteFileAtomic(shading_csv, shading.str());
  }
  return path;
}

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

void PlotPanel::ShadeX(double x0, double x1, const cv::Scalar& colour,
                       const std::string& label) {
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
